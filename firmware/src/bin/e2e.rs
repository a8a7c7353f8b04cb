//! e2e image: see `firmware::target::images::e2e`.
#![no_std]
#![no_main]

firmware::qemu_image!(firmware::target::images::e2e);
