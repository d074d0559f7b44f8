//! The export stage: a scene's equations as source that needs nothing of lagrange, over the
//! programs `engine::numbers` lowers. One walk over a program prints it as straight-line
//! source, spelled by a dialect per language ([`source`], with [`source::rust`] and
//! [`source::c`]); [`codegen`] gathers a scene's programs once and prints them as a Rust
//! module or a C99 header and source; [`fmu`] says what an FMI 2.0 FMU of the scene holds:
//! its model description, the generated C, the FMI wrapper and the DOP853 stepper with `sim`'s
//! tableau.
//!
//! It reads no files and compiles nothing: the text comes back as strings, and a front end
//! writes it, builds an FMU's binary and zips the archive. Nothing below it depends on it.

pub mod codegen;
pub mod fmu;
pub mod source;
