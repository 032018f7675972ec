//! The scene fuzzer's corpus (tests/fuzz/corpus/scene), replayed on stable Rust with the fuzz target's own
//! checks: every input the fuzzer kept, and every crash it found, stays a regression test.

#[path = "fuzz/check.rs"]
mod check;

use std::path::Path;

use energywave::scene::Scene;

#[test]
fn every_corpus_input_holds_the_fuzz_properties() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz/corpus/scene");
    let mut entries: Vec<_> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    let (mut accepted, mut refused) = (0, 0);
    for path in &entries {
        let bytes = std::fs::read(path).unwrap();
        let result = std::panic::catch_unwind(|| check::check_scene_bytes(&bytes));
        assert!(result.is_ok(), "{} breaks a property", path.display());
        match Scene::parse_bytes(&bytes, Path::new(check::NAME)) {
            Ok(_) => accepted += 1,
            Err(_) => refused += 1,
        }
        let name = path.file_name().unwrap().to_string_lossy();
        if name.starts_with("preset-") {
            assert!(
                Scene::parse_bytes(&bytes, path).is_ok(),
                "{name}: a shipped preset is refused"
            );
        }
    }
    // The corpus exercises both sides of the validator.
    assert!(
        accepted >= 13 && refused >= 7,
        "{accepted} accepted, {refused} refused"
    );
}
