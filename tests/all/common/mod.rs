//! What the test modules share: fixtures, helpers and the crate's counting allocator.
#![allow(dead_code)]

pub mod alloc;
pub mod cli;
pub mod mcap_check;
pub mod model_fixtures;
pub mod paper;
pub mod rng;
pub mod shared_file;
