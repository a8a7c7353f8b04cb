//! golden image: see `firmware::target::images::golden`.
#![no_std]
#![no_main]

firmware::qemu_image!(firmware::target::images::golden);
