//! The preview's reflections in curved mirrors by Fermat's principle: the solver (`fermat`,
//! the CPU side, f64) and its GPU kernels (`kernel`).

pub mod fermat;
pub mod kernel;
