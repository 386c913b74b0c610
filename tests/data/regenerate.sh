#!/usr/bin/env bash
# Regenerates tests/data/fixture.mcap, the synthetic run of tests/all/log.rs, written by the
# current LogWriter. Run it when the log format changes on purpose, and commit the result:
#   bash tests/data/regenerate.sh
set -euo pipefail
cd "$(dirname "$0")/../.."
cargo test --test all -- --ignored --exact log::regenerate_fixture --nocapture
