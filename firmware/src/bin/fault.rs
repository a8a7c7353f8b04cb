//! fault image: see `firmware::target::images::fault`.
#![no_std]
#![no_main]

firmware::qemu_image!(firmware::target::images::fault);
