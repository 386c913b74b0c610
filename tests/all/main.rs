//! The integration tests, in one crate: a module per concern, each a former test file of
//! its own. One test binary instead of fifty: each binary linked the whole library and its
//! dependencies, and a clean `cargo test --release` spent most of its time in those links
//! (issue 16). `common` holds what the modules share, among it the crate's global
//! allocator, which counts each thread's allocations for the allocation tests.
//!
//! Tests of one module run with a filter on their path: `cargo test --release --test all
//! sim_persistent::`. Tests in this binary run on parallel threads: a test must not change
//! process-wide state (environment, current directory, signal handlers, the panic hook)
//! that another could see, and writes only in a folder of its own (`common::cli::TempDir`).
//! `tests/live.rs` (feature `live`) is a binary of its own (see Cargo.toml).

mod common;

mod accumulation;
mod articulated;
mod broad_phase;
mod chain_floor;
mod cli_impact;
mod cli_regress;
mod cli_repair;
mod cli_run;
mod contact_gap;
mod contact_points;
mod dense_on_demand;
mod dynamics;
mod event_stand_ins;
mod events;
mod fuzz_scenes;
mod golden_scenes;
mod impact_laws;
mod impact_second_method;
mod integrate;
mod issue_12_corrupted_logs;
mod issue_12_impact_lines;
mod issue_12_impact_scale;
mod issue_12_long_run_memory;
mod issue_12_messages;
mod issue_12_step_floor;
mod issue_12_sweep;
mod issue_4_spurious_crossing_after_impact;
mod kinematics;
mod lcp_alloc;
mod lcp_lemke;
mod log;
mod long_runs;
mod many_contacts;
mod model;
mod model_alloc;
mod moreau_jean;
mod nonholonomic;
mod paper_table_2;
mod regions;
mod regress;
mod repair;
mod samples_or_not;
mod scene;
mod scene_check;
mod sim_alloc;
mod sim_bouncing_ball;
mod sim_energy;
mod sim_falling_rod;
mod sim_first_contact;
mod sim_kane;
mod sim_log;
mod sim_persistent;
mod sim_two_discs;
mod spin_drops;
mod sweep;
mod tree_matrix;
mod unit;
mod workprec;
