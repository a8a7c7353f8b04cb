//! panic image: see `firmware::target::images::panic`.
#![no_std]
#![no_main]

firmware::qemu_image!(firmware::target::images::panic);
