//! bench image: see `firmware::target::images::bench`.
#![no_std]
#![no_main]

firmware::qemu_image!(firmware::target::images::bench);
