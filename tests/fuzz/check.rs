//! What must hold for any bytes given as a scene file, shared by the fuzz target and the corpus replay test:
//! parsing never panics; a refusal names the file and, for a problem inside the text, a place in it; an
//! accepted scene is finite and saves to text that loads back to the same scene.

use std::path::Path;

use energywave::scene::{Scene, SceneError};

pub const NAME: &str = "fuzzed.toml";

pub fn check_scene_bytes(bytes: &[u8]) {
    let path = Path::new(NAME);
    match Scene::parse_bytes(bytes, path) {
        Ok(scene) => {
            let text = scene.to_toml();
            let again = Scene::parse(&text, path).unwrap_or_else(|e| {
                panic!("an accepted scene saves to text that fails to load: {e}\n{text}")
            });
            assert_eq!(again, scene, "save and load changed the scene\n{text}");
            assert!(
                scene.camera.eye.is_finite() && scene.camera.target.is_finite(),
                "non-finite camera accepted"
            );
        }
        Err(e) => {
            let message = e.to_string();
            assert!(
                message.contains(NAME),
                "the error does not name the file: {message}"
            );
            if let SceneError::Invalid { problems, .. } = &e {
                assert!(
                    !problems.is_empty(),
                    "an invalid scene with no problem: {message}"
                );
                for p in problems {
                    assert!(
                        !p.message.trim().is_empty(),
                        "a problem without a message: {message}"
                    );
                    assert!(
                        p.location.is_some() || !p.field.is_empty(),
                        "a problem with neither a place nor a field: {message}"
                    );
                }
            }
        }
    }
}
