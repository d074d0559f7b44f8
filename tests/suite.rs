//! The workspace-level tests in one binary: each module is a theme (a file beside this one).
//!
//! One binary rather than one per file, because each test binary links the whole house (the
//! engine, the command line and everything under them): forty of them spent most of
//! `cargo test`'s time in the linker, and ran one after another where the modules of one
//! binary run side by side. `ensemble_allocations` keeps a binary of its own: it installs a
//! counting global allocator, which would count every other test's allocations too.

mod algebra;
mod along;
mod andrews;
mod animate;
mod bicycle;
mod car_axis;
mod check;
mod codegen;
mod codegen_c;
mod codegen_contacts;
mod codegen_hostile;
mod constraints;
mod contacts;
mod control;
mod derive;
mod docs;
mod drive;
mod ensemble;
mod errors;
mod extremes;
mod fitting;
mod fmu;
mod friction;
mod gallery;
mod hold;
mod inverse_dynamics;
mod jacobian;
mod jit;
mod linearize;
mod lockstep;
mod lockstep_edges;
mod many;
mod orbits;
mod radau;
mod random_scenes;
mod rates;
mod recursive;
mod resolutions;
mod run_faults;
mod sensitivities;
mod simulate;
mod space;
mod starts;
mod stiff;
mod tidy;
mod tolerance;
mod units;
