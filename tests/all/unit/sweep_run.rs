//! The unit tests of `sweep::run` (`src/sweep/run.rs`).

// The source module's own imports.

use ricochet::sweep::run::*;

#[test]
fn a_panic_is_a_row_with_its_message() {
    // The panic's message goes to the hook (stderr) too; keep the test output quiet.
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let got = caught(|| panic!("index out of bounds: the len is 3 but the index is 7"));
    let formatted = caught(|| panic!("{} {}", "formatted", 42));
    std::panic::set_hook(hook);
    assert_eq!(
        got,
        Err(NotRun {
            stop: "panic",
            detail: "the run panicked: index out of bounds: the len is 3 but the index is 7"
                .to_owned()
        })
    );
    assert_eq!(
        formatted.unwrap_err().detail,
        "the run panicked: formatted 42"
    );
}
