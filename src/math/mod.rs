//! Numeric building blocks shared, function for function, with the WGSL kernels.

pub mod rng;
pub mod sampling;
