//! The science layer: diagnosis, identifiability and excitation planning.

pub mod diagnose;
pub mod excitation;
pub mod identify;
