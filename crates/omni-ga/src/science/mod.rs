//! The science layer: diagnosis ([`diagnose`]), identifiability ([`identify`]), excitation planning
//! ([`excitation`]) and motion coverage ([`coverage`]). Each returns structured findings; their words are made in one place, [`text`].
//!
//! `identify` depends only on omni-kin (the fit layer uses it for the truncated update); `diagnose` and
//! `excitation` build on the fit layer's [`crate::fit::CalibrationProblem`].

pub mod coverage;
pub mod diagnose;
pub mod excitation;
pub mod explore;
pub(crate) mod heaviest_first;
pub mod identify;
pub mod text;
