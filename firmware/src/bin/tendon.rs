//! tendon image: see `firmware::target::images::tendon`.
#![no_std]
#![no_main]

firmware::qemu_image!(firmware::target::images::tendon);
