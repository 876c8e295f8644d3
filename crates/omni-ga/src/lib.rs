//! omni-ga
