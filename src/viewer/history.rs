//! Undo and redo over whole-scene snapshots.
//!
//! An edit is committed once it settles (no drag in progress), so a drag of a slider or a handle is one undo
//! step. The camera is the view, not the effect: moving it (by mouse or by numbers) is never an undo step, and
//! undo and redo leave it where it is.

use crate::scene::Scene;

/// Most snapshots kept for undo.
const MAX_UNDO: usize = 200;

/// The undo and redo stacks around the last committed scene.
#[derive(Debug)]
pub struct History {
    committed: Scene,
    undo: Vec<Scene>,
    redo: Vec<Scene>,
}

impl History {
    /// Starts with `scene` committed and nothing to undo.
    pub fn new(scene: &Scene) -> Self {
        Self {
            committed: scene.clone(),
            undo: Vec::new(),
            redo: Vec::new(),
        }
    }

    /// Records `scene` as an undo step if it differs from the last committed state. Call when no edit is in
    /// progress. Returns true when a step was recorded.
    pub fn commit(&mut self, scene: &Scene) -> bool {
        self.committed.camera = scene.camera.clone();
        if *scene == self.committed {
            return false;
        }
        let previous = std::mem::replace(&mut self.committed, scene.clone());
        self.undo.push(previous);
        if self.undo.len() > MAX_UNDO {
            self.undo.remove(0);
        }
        self.redo.clear();
        true
    }

    /// Steps back: `scene` becomes the previous committed state (uncommitted edits are dropped). Returns
    /// false when there is nothing to undo.
    pub fn undo(&mut self, scene: &mut Scene) -> bool {
        let Some(previous) = self.undo.pop() else {
            return false;
        };
        let current = std::mem::replace(&mut self.committed, previous);
        self.redo.push(current);
        self.restore(scene);
        true
    }

    /// Steps forward again. Returns false when there is nothing to redo.
    pub fn redo(&mut self, scene: &mut Scene) -> bool {
        let Some(next) = self.redo.pop() else {
            return false;
        };
        let current = std::mem::replace(&mut self.committed, next);
        self.undo.push(current);
        self.restore(scene);
        true
    }

    /// Sets `scene` to the committed state, keeping its camera.
    fn restore(&mut self, scene: &mut Scene) {
        self.committed.camera = scene.camera.clone();
        *scene = self.committed.clone();
    }

    /// Forgets everything and starts again from `scene` (after opening a file).
    pub fn reset(&mut self, scene: &Scene) {
        *self = Self::new(scene);
    }

    pub fn can_undo(&self) -> bool {
        !self.undo.is_empty()
    }

    pub fn can_redo(&self) -> bool {
        !self.redo.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn undo_and_redo_walk_the_committed_states() {
        let mut scene = Scene::default_scene();
        let original = scene.clone();
        let mut h = History::new(&scene);
        assert!(!h.commit(&scene), "no change, no step");
        scene.integration.divisions = 100;
        assert!(h.commit(&scene));
        let first = scene.clone();
        scene.sources.curves[0].coefficient = 9.0;
        assert!(h.commit(&scene));
        let second = scene.clone();
        assert!(h.undo(&mut scene));
        assert_eq!(scene, first);
        assert!(h.undo(&mut scene));
        assert_eq!(scene, original);
        assert!(!h.undo(&mut scene));
        assert!(h.redo(&mut scene));
        assert!(h.redo(&mut scene));
        assert_eq!(scene, second);
        assert!(!h.redo(&mut scene));
        // A new edit after an undo drops the redo branch.
        h.undo(&mut scene);
        scene.colors.energy = [1.0, 0.0, 0.0];
        h.commit(&scene);
        assert!(!h.can_redo());
    }

    #[test]
    fn the_camera_is_not_an_undo_step_and_stays_put() {
        let mut scene = Scene::default_scene();
        let mut h = History::new(&scene);
        scene.camera.eye.x += 3.0;
        assert!(!h.commit(&scene));
        assert!(!h.can_undo());
        scene.integration.decay_length = 3.0;
        assert!(h.commit(&scene));
        scene.camera.eye.y += 1.0;
        let eye = scene.camera.eye;
        assert!(h.undo(&mut scene));
        assert_eq!(
            scene.integration.decay_length,
            Scene::default_scene().integration.decay_length
        );
        assert_eq!(scene.camera.eye, eye);
    }
}
