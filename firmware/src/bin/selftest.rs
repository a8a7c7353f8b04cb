//! selftest image: see `firmware::target::images::selftest`.
#![no_std]
#![no_main]

firmware::qemu_image!(firmware::target::images::selftest);
