//! robot image: see `firmware::target::images::robot`.
#![no_std]
#![no_main]

firmware::qemu_image!(firmware::target::images::robot);
