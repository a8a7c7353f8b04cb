//! Puts the repository's `memory.x` (STM32F405 memory map) on the linker's search path for target
//! builds, and adds defmt's linker script to the images that log with defmt.

use std::{env, fs, path::PathBuf};

/// Images that log with defmt (over RTT).
const DEFMT_IMAGES: &[&str] = &["estimator", "board"];

fn main() -> Result<(), Box<dyn std::error::Error>> {
    println!("cargo:rerun-if-changed=build.rs");
    if env::var("CARGO_CFG_TARGET_OS").as_deref() != Ok("none") {
        return Ok(());
    }
    let manifest = PathBuf::from(env::var("CARGO_MANIFEST_DIR")?);
    let memory = manifest.join("..").join("memory.x");
    println!("cargo:rerun-if-changed={}", memory.display());
    let out = PathBuf::from(env::var("OUT_DIR")?);
    fs::copy(&memory, out.join("memory.x"))?;
    println!("cargo:rustc-link-search={}", out.display());
    // defmt's linker script needs a global logger: only the images that log with defmt get it.
    for image in DEFMT_IMAGES {
        println!("cargo:rustc-link-arg-bin={image}=-Tdefmt.x");
    }
    Ok(())
}
