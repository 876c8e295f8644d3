//! omni-cli
