//! The library's unit tests: each file holds the tests of one module of `src/` (its path
//! with `_` for `::`), moved out of the library so that `cargo test` compiles the library
//! once (ARCHITECTURE, "Tests").

mod articulated;
mod contact_gap;
mod contact_manifold;
mod contact_penetration;
mod dynamics;
mod events_bound;
mod events_illinois;
mod events_locate;
mod impact_double_double;
mod impact_path;
mod impact_scale;
mod impact_stronge;
mod integrate_control;
mod integrate_tableau;
mod lcp;
mod lcp_enumerate;
mod lcp_lemke;
mod lcp_repair;
mod linalg;
mod log_draw;
mod log_foxglove;
mod log_records;
mod log_repair_lz4;
mod log_run;
mod log_samples;
mod log_sink;
mod math;
mod model_pairs;
mod model_spatial;
mod pgs;
mod regress_drift;
mod regress_golden;
mod regress_layout;
mod regress_overrides;
mod scene_ranges;
mod scene_units;
mod sim_gaps;
mod sim_pair_map;
mod sim_persistent;
mod sweep_run;
mod tree_matrix;
mod workprec_chart;

use ricochet::math::Real;

/// Numbers uniform in `[0, 1)` (53 bits each) from the xorshift64 generator started at
/// `state` (not 0): the random inputs of the library's tests.
pub(crate) fn uniform_numbers(mut state: u64) -> impl FnMut() -> Real {
    move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as Real / (1u64 << 53) as Real
    }
}
