//! estimator image: the production loop (encoders, validation, warm f32 estimator, defmt output)
//! on the recorded encoder trajectory; see `firmware::target::images::estimator`.
#![no_std]
#![no_main]

use defmt_rtt as _;

firmware::qemu_image!(firmware::target::images::estimator);
