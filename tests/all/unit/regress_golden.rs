//! The unit tests of `regress::golden` (`src/regress/golden.rs`).

// The source module's own imports.
use std::path::{Path, PathBuf};

use ricochet::regress::golden::*;

#[test]
fn relative_paths_climb_to_the_common_folder() {
    let base = std::env::temp_dir().join(format!("ricochet-relative-{}", std::process::id()));
    let (golden, scenes) = (base.join("tests/golden"), base.join("scenes"));
    std::fs::create_dir_all(&golden).unwrap();
    std::fs::create_dir_all(&scenes).unwrap();
    let scene = scenes.join("ball.toml");
    std::fs::write(&scene, "").unwrap();
    assert_eq!(relative_path(&golden, &scene), "../../scenes/ball.toml");
    assert_eq!(relative_path(&scenes, &scene), "ball.toml");
    assert_eq!(
        Path::new("x/tests/golden").join("../../scenes/ball.toml"),
        PathBuf::from("x/tests/golden/../../scenes/ball.toml")
    );
    let _ = std::fs::remove_dir_all(&base);
}

#[test]
fn golden_files_are_named_after_the_scene_file() {
    assert_eq!(
        golden_path(Path::new("g"), Path::new("scenes/chain.toml")),
        PathBuf::from("g/chain.golden.json")
    );
}
