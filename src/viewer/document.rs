//! The open scene as a document: where it lives, whether it has unsaved changes, saving atomically, reloading
//! when the file changes on disk, and where screenshots go.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use crate::output::{self, OutputError};
use crate::scene::{Scene, SceneError, format};

/// How often the file's modification time is checked for hot reload.
const POLL_INTERVAL: Duration = Duration::from_millis(400);

/// What a look at the file on disk found.
#[derive(Debug)]
pub enum DiskChange {
    /// The file changed and was loaded (the document had no unsaved changes).
    Reloaded,
    /// The file changed but does not load: the current scene is kept.
    Invalid(String),
    /// The file changed while the document has unsaved edits: nothing replaced, the user decides.
    Conflict,
}

/// The scene being edited and its file.
#[derive(Debug)]
pub struct Document {
    pub scene: Scene,
    path: Option<PathBuf>,
    /// The scene as it is in the file (or the embedded default): the reference for "unsaved changes".
    saved: Scene,
    /// The file's text, which loads as `saved`: a save writes the changes into it (`scene::format`), keeping
    /// its comments and layout. `None` for a scene without a file.
    source: Option<String>,
    disk_mtime: Option<SystemTime>,
    last_poll: Option<Instant>,
    /// A valid version from disk waiting while the document has unsaved edits.
    pub pending_reload: Option<Scene>,
    /// The text of the version from disk last read.
    pending_source: Option<String>,
    /// Why the last change on disk could not be loaded.
    pub disk_error: Option<String>,
}

fn mtime(path: &Path) -> Option<SystemTime> {
    std::fs::metadata(path).and_then(|m| m.modified()).ok()
}

impl Document {
    /// A document for `scene` read from `path` (or the embedded default scene without one).
    pub fn new(scene: Scene, path: Option<PathBuf>) -> Self {
        let disk_mtime = path.as_deref().and_then(mtime);
        // The file's text, where it still says this scene.
        let source = path
            .as_deref()
            .and_then(|p| std::fs::read_to_string(p).ok())
            .filter(|text| {
                Scene::parse(text, path.as_deref().unwrap_or(Path::new("")))
                    .is_ok_and(|s| s == scene)
            });
        Self {
            saved: scene.clone(),
            source,
            scene,
            path,
            disk_mtime,
            last_poll: None,
            pending_reload: None,
            pending_source: None,
            disk_error: None,
        }
    }

    /// Opens a scene file.
    pub fn open(path: &Path) -> Result<Self, SceneError> {
        Ok(Self::new(Scene::load(path)?, Some(path.to_owned())))
    }

    /// The file, if the scene has one.
    pub fn path(&self) -> Option<&Path> {
        self.path.as_deref()
    }

    /// The scene as last loaded or saved.
    pub fn saved(&self) -> &Scene {
        &self.saved
    }

    /// True when the effect differs from its file. The view does not count: looking is not editing. (The
    /// camera is saved with the scene when the user saves, and a reload keeps a view the user moved.)
    pub fn is_dirty(&self) -> bool {
        !same_effect(&self.scene, &self.saved)
    }

    /// True when the camera differs from the file's: the user moved the view.
    pub fn view_moved(&self) -> bool {
        self.scene.camera != self.saved.camera
    }

    /// The name to show: the file name (or "default scene") with `*` when there are unsaved changes.
    pub fn title(&self) -> String {
        let name = self
            .path
            .as_ref()
            .and_then(|p| p.file_name())
            .map_or("default scene".to_owned(), |n| {
                n.to_string_lossy().into_owned()
            });
        if self.is_dirty() {
            format!("{name} *")
        } else {
            name
        }
    }

    /// Saves to the document's file; `Ok(false)` when it has none yet (use `save_as`).
    pub fn save(&mut self) -> Result<bool, OutputError> {
        let Some(path) = self.path.clone() else {
            return Ok(false);
        };
        self.save_as(&path)?;
        Ok(true)
    }

    /// Saves to `path` (atomically: a temporary file beside it, then a rename) and makes it the document's file.
    /// The file's own text gets the changes written into it, its comments, order and layout kept; a scene
    /// without a file is written fresh (`scene::format`).
    pub fn save_as(&mut self, path: &Path) -> Result<(), OutputError> {
        // Into another folder, a mesh's or PLY file's relative path is rewritten to name the same file from there.
        let folder = |p: Option<&Path>| {
            p.and_then(Path::parent)
                .map_or_else(PathBuf::new, Path::to_path_buf)
        };
        let scene = (self.scene).rebased(&folder(self.path.as_deref()), &folder(Some(path)));
        let text = match &self.source {
            Some(source) => format::update_text(source, &self.saved, &scene, path),
            None => format::fresh_text(&scene, path),
        };
        output::write_atomically(path, text.as_bytes())?;
        self.scene = scene;
        self.source = Some(text);
        self.path = Some(path.to_owned());
        self.saved = self.scene.clone();
        self.disk_mtime = mtime(path);
        self.pending_reload = None;
        self.disk_error = None;
        Ok(())
    }

    /// Checks the file for changes made outside the viewer (at most every `POLL_INTERVAL`).
    pub fn poll_disk(&mut self, now: Instant) -> Option<DiskChange> {
        if self
            .last_poll
            .is_some_and(|t| now.duration_since(t) < POLL_INTERVAL)
        {
            return None;
        }
        self.last_poll = Some(now);
        self.check_disk()
    }

    /// Whether the file's modification time differs from the one last read or written: a stat, nothing read
    /// (the window checks this while idle instead of drawing frames).
    pub fn changed_on_disk(&self) -> bool {
        self.path
            .as_deref()
            .and_then(mtime)
            .is_some_and(|m| Some(m) != self.disk_mtime)
    }

    /// Checks the file for changes now.
    pub fn check_disk(&mut self) -> Option<DiskChange> {
        let path = self.path.clone()?;
        let current = mtime(&path);
        if current.is_none() || current == self.disk_mtime {
            return None;
        }
        self.disk_mtime = current;
        let text = std::fs::read_to_string(&path).ok();
        match Scene::load(&path) {
            Err(e) => {
                self.disk_error = Some(e.to_string());
                Some(DiskChange::Invalid(e.to_string()))
            }
            Ok(scene) if scene == self.saved => {
                self.disk_error = None;
                None
            }
            Ok(scene) => {
                self.disk_error = None;
                // The text that loads as it (read just before; another write between the two reads would
                // only cost the layout).
                self.pending_source =
                    text.filter(|t| Scene::parse(t, &path).is_ok_and(|s| s == scene));
                if self.is_dirty() {
                    self.pending_reload = Some(scene);
                    Some(DiskChange::Conflict)
                } else {
                    self.take_from_disk(scene);
                    Some(DiskChange::Reloaded)
                }
            }
        }
    }

    /// Takes the version waiting on disk, dropping unsaved edits.
    pub fn accept_reload(&mut self) {
        if let Some(scene) = self.pending_reload.take() {
            self.take_from_disk(scene);
        }
    }

    /// The file's new content becomes the document's, keeping the view where the user moved it.
    fn take_from_disk(&mut self, scene: Scene) {
        let view = self.view_moved().then(|| self.scene.camera.clone());
        self.source = self.pending_source.take();
        self.saved = scene.clone();
        self.scene = scene;
        if let Some(camera) = view {
            self.scene.camera = camera;
        }
    }

    /// The folder screenshots go to, absolute, so that the UI can say where: beside the scene file, or the working
    /// directory for a scene without one (the embedded default, a scene not saved yet).
    pub fn screenshot_dir(&self) -> PathBuf {
        let dir = match &self.path {
            Some(p) => p
                .parent()
                .filter(|d| !d.as_os_str().is_empty())
                .unwrap_or(Path::new("."))
                .to_owned(),
            None => PathBuf::from("."),
        };
        std::path::absolute(&dir).unwrap_or(dir)
    }

    /// Where a screenshot taken now goes: into `screenshot_dir`, named after the scene and the UTC time, never an
    /// existing file.
    pub fn screenshot_path(&self, now: SystemTime) -> PathBuf {
        let stem = match &self.path {
            Some(p) => p
                .file_stem()
                .map_or("scene".into(), |s| s.to_string_lossy().into_owned()),
            None => "energywave".to_owned(),
        };
        unused_path(
            &self.screenshot_dir(),
            &format!("{stem}-{}", timestamp(now)),
            "png",
        )
    }
}

/// True when `a` and `b` are the same effect, whatever their cameras: every other part equal (written out, so
/// that a part added to the scene is not forgotten here), nothing cloned (the title asks every frame).
fn same_effect(a: &Scene, b: &Scene) -> bool {
    let Scene {
        camera: _,
        billboard,
        integration,
        colors,
        glare,
        sources,
        objects,
        particles,
        slice_width,
        animation,
    } = a;
    *billboard == b.billboard
        && *integration == b.integration
        && *colors == b.colors
        && *glare == b.glare
        && *sources == b.sources
        && *objects == b.objects
        && *particles == b.particles
        && *slice_width == b.slice_width
        && *animation == b.animation
}

/// `dir/base.ext`, or `dir/base-2.ext`, `dir/base-3.ext`, ... the first that does not exist.
pub fn unused_path(dir: &Path, base: &str, ext: &str) -> PathBuf {
    let first = dir.join(format!("{base}.{ext}"));
    if !first.exists() {
        return first;
    }
    (2..)
        .map(|k| dir.join(format!("{base}-{k}.{ext}")))
        .find(|p| !p.exists())
        .expect("some suffix is free")
}

/// `YYYYMMDD-HHMMSS` in UTC.
pub fn timestamp(t: SystemTime) -> String {
    let secs = t.duration_since(UNIX_EPOCH).map_or(0, |d| d.as_secs()) as i64;
    let (days, rem) = (secs.div_euclid(86_400), secs.rem_euclid(86_400));
    // Civil date from days since 1970-01-01 (H. Hinnant's algorithm).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + (month <= 2) as i64;
    format!(
        "{year:04}{month:02}{day:02}-{:02}{:02}{:02}",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tmp(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("energywave-doc-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn timestamps_are_utc_calendar_times() {
        assert_eq!(timestamp(UNIX_EPOCH), "19700101-000000");
        // 2026-11-22 02:11:55 UTC.
        assert_eq!(
            timestamp(UNIX_EPOCH + Duration::from_secs(1_795_313_515)),
            "20261122-021155"
        );
        // A leap day.
        assert_eq!(
            timestamp(UNIX_EPOCH + Duration::from_secs(951_782_400)),
            "20000229-000000"
        );
    }

    #[test]
    fn screenshots_never_overwrite() {
        let dir = tmp("shots");
        let scene_path = dir.join("ring.toml");
        std::fs::write(&scene_path, Scene::default_scene().to_toml()).unwrap();
        let doc = Document::open(&scene_path).unwrap();
        let now = UNIX_EPOCH + Duration::from_secs(1_795_313_515);
        let first = doc.screenshot_path(now);
        assert_eq!(first, dir.join("ring-20261122-021155.png"));
        std::fs::write(&first, b"x").unwrap();
        assert_eq!(
            doc.screenshot_path(now),
            dir.join("ring-20261122-021155-2.png")
        );
    }

    /// Dates the file's last change at `t` (a change within the same clock tick would go unseen).
    fn set_mtime(path: &Path, t: SystemTime) {
        std::fs::File::options()
            .write(true)
            .open(path)
            .unwrap()
            .set_modified(t)
            .unwrap();
    }

    #[test]
    fn looking_is_not_editing_and_a_reload_keeps_the_view() {
        let dir = tmp("view");
        let path = dir.join("look.toml");
        std::fs::write(&path, Scene::default_scene().to_toml()).unwrap();
        let mut doc = Document::open(&path).unwrap();
        doc.scene.camera.eye.x += 1.5;
        assert!(
            !doc.is_dirty() && !doc.title().ends_with('*'),
            "an orbit is no edit"
        );
        assert!(doc.view_moved());
        // The file changes on disk: it reloads (no edits to lose), and the view stays where it was moved.
        let eye = doc.scene.camera.eye;
        let mut edited = Scene::default_scene();
        edited.sources.tori.clear();
        edited.camera.eye.y += 3.0;
        std::thread::sleep(Duration::from_millis(20));
        std::fs::write(&path, edited.to_toml()).unwrap();
        let t = std::time::SystemTime::now() + Duration::from_secs(5);
        set_mtime(&path, t);
        assert!(matches!(doc.check_disk(), Some(DiskChange::Reloaded)));
        assert_eq!(doc.scene.sources, edited.sources);
        assert_eq!(doc.scene.camera.eye, eye, "the view the user moved");
        assert!(!doc.is_dirty());
        // Saving writes the view with the effect.
        doc.save().unwrap();
        assert_eq!(Scene::load(&path).unwrap().camera.eye, eye);
        // An untouched view follows the file.
        let mut again = Document::open(&path).unwrap();
        let mut moved = again.scene.clone();
        moved.camera.eye.z += 2.0;
        std::fs::write(&path, moved.to_toml()).unwrap();
        set_mtime(&path, t + Duration::from_secs(5));
        assert!(matches!(again.check_disk(), Some(DiskChange::Reloaded)));
        assert_eq!(again.scene.camera, moved.camera);
    }

    #[test]
    fn save_then_open_is_lossless_and_clears_the_dirty_mark() {
        let dir = tmp("save");
        let mut doc = Document::new(Scene::default_scene(), None);
        doc.scene.sources.curves[0].control_points[1].y = 0.123456789012345;
        doc.scene.colors.background = [0.1, 0.2, 0.3];
        assert!(doc.is_dirty() && doc.title().ends_with('*'));
        assert!(!doc.save().unwrap(), "no file yet");
        let path = dir.join("edited.toml");
        doc.save_as(&path).unwrap();
        assert!(!doc.is_dirty());
        assert_eq!(doc.title(), "edited.toml");
        let again = Document::open(&path).unwrap();
        assert_eq!(again.scene, doc.scene);
        // Nothing but the file itself is left in the directory (the temporary file was renamed).
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
    }

    #[test]
    fn hot_reload_takes_valid_files_and_keeps_the_last_good_scene() {
        let dir = tmp("reload");
        let path = dir.join("live.toml");
        let mut scene = Scene::default_scene();
        std::fs::write(&path, scene.to_toml()).unwrap();
        let mut doc = Document::open(&path).unwrap();
        assert!(doc.check_disk().is_none(), "unchanged file");
        // A valid change is loaded.
        scene.integration.divisions = 64;
        write_later(&path, &scene.to_toml());
        assert!(matches!(doc.check_disk(), Some(DiskChange::Reloaded)));
        assert_eq!(doc.scene.integration.divisions, 64);
        assert!(!doc.is_dirty());
        // A broken (half-written) file keeps the last good scene and reports why.
        write_later(
            &path,
            "[integration]\ndivisions = 6\n[[curves]]\ncontrol_points = [[0, 0, 0], [1,",
        );
        assert!(matches!(doc.check_disk(), Some(DiskChange::Invalid(_))));
        assert_eq!(doc.scene.integration.divisions, 64);
        assert!(doc.disk_error.as_deref().unwrap().contains("live.toml"));
        // With unsaved edits, a change on disk waits for the user.
        doc.scene.integration.decay_length = 3.0;
        scene.integration.divisions = 32;
        write_later(&path, &scene.to_toml());
        assert!(matches!(doc.check_disk(), Some(DiskChange::Conflict)));
        assert_eq!(doc.scene.integration.decay_length, 3.0);
        doc.accept_reload();
        assert_eq!(
            (
                doc.scene.integration.divisions,
                doc.scene.integration.decay_length
            ),
            (32, scene.integration.decay_length)
        );
    }

    /// Writes so that the modification time differs from the previous write's.
    fn write_later(path: &Path, text: &str) {
        let before = mtime(path);
        loop {
            std::fs::write(path, text).unwrap();
            if mtime(path) != before {
                return;
            }
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    #[test]
    fn save_as_into_another_folder_keeps_the_meshes_and_particle_files_it_names() {
        // paper_two_particles names "two_particles.ply" beside it: saved into another folder, the file must still
        // name it (as "../..." or absolute), and load with the same particles.
        let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes");
        let dir = tmp("save-as-elsewhere");
        let copy = dir.join("orig");
        std::fs::create_dir_all(&copy).unwrap();
        for f in ["paper_two_particles.toml", "two_particles.ply"] {
            std::fs::copy(scenes.join(f), copy.join(f)).unwrap();
        }
        let mut doc = Document::open(&copy.join("paper_two_particles.toml")).unwrap();
        let before = doc.scene.clone();
        let elsewhere = dir.join("other").join("deeper");
        std::fs::create_dir_all(&elsewhere).unwrap();
        let saved = elsewhere.join("moved.toml");
        doc.save_as(&saved).unwrap();
        let text = std::fs::read_to_string(&saved).unwrap();
        assert!(text.contains("../../orig/two_particles.ply"), "{text}");
        let loaded = Scene::load(&saved).unwrap_or_else(|e| panic!("{e}\n{text}"));
        assert_eq!(loaded.particles.len(), before.particles.len());
        for (a, b) in loaded.particles.iter().zip(&before.particles) {
            let (a, b) = (a.particles(&loaded.sources), b.particles(&before.sources));
            assert!(!a.is_empty() && a == b);
        }
        // Saved back beside the file it names, the path is as short as it was.
        doc.save_as(&copy.join("again.toml")).unwrap();
        let again = std::fs::read_to_string(copy.join("again.toml")).unwrap();
        assert!(again.contains("file = \"two_particles.ply\""), "{again}");
    }
}
