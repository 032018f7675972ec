//! Scene text a person can read: a scene written back into its file's own text, keeping the file's comments,
//! order and layout and changing only what the user changed (`update_text`), or written fresh with small
//! arrays on one line (`fresh_text`). Numbers are as short as reads them back (f64's shortest round trip).
//! Both are checked: the text written reads back as the scene, or a plainer form is written instead.

use std::path::Path;

use toml_edit::{Array, DocumentMut, Item, Table, Value};

use super::Scene;

/// Arrays whose one-line form is longer than this (characters) get one element a line.
const ONE_LINE: usize = 96;

/// `scene` as fresh TOML text: every setting, one key a line, small arrays on one line. `path` is where the text
/// is to be read from (a mesh's or a PLY file's relative path is read against its folder).
pub fn fresh_text(scene: &Scene, path: &Path) -> String {
    let generated = scene.to_toml();
    let Ok(mut doc) = generated.parse::<DocumentMut>() else {
        return generated;
    };
    tidy_table(doc.as_table_mut());
    let text = doc.to_string();
    if reads_back(&text, scene, path) {
        text
    } else {
        generated
    }
}

/// The file's text `original`, which loads as `saved`, with `scene`'s changes from `saved` written into it:
/// values the user left alone keep their text (a direction written `[1, 0.25, 0]` stays so, though it loads
/// normalised), comments and the order of keys and tables stay, sources added are appended and sources removed
/// dropped. A decay length the file derives (from `nu` and its camera) is written out when it would derive
/// differently now (the camera moved). Should the text still not read back as the scene, `fresh_text`. `path`
/// is where the text is to be read from, as `fresh_text`'s.
pub fn update_text(original: &str, saved: &Scene, scene: &Scene, path: &Path) -> String {
    let Ok(doc) = original.parse::<DocumentMut>() else {
        return fresh_text(scene, path);
    };
    let (Ok(old), Ok(new)) = (
        saved.to_toml().parse::<DocumentMut>(),
        scene.to_toml().parse::<DocumentMut>(),
    ) else {
        return fresh_text(scene, path);
    };
    let mut merged = doc;
    merge_table(merged.as_table_mut(), Some(old.as_table()), new.as_table());
    let text = merged.to_string();
    if reads_back(&text, scene, path) {
        return text;
    }
    // The decay length, derived from the camera, pinned.
    if let Some(decay) = new
        .get("integration")
        .and_then(|i| i.get("decay_length"))
        .and_then(Item::as_value)
    {
        let table = merged
            .entry("integration")
            .or_insert_with(|| Item::Table(Table::new()));
        if let Some(t) = table.as_table_mut() {
            t.remove("nu");
            t.insert("decay_length", Item::Value(decay.clone()));
        }
        let text = merged.to_string();
        if reads_back(&text, scene, path) {
            return text;
        }
    }
    fresh_text(scene, path)
}

/// True when `text` loads as `scene`.
fn reads_back(text: &str, scene: &Scene, path: &Path) -> bool {
    Scene::parse(text, path).is_ok_and(|s| s == *scene)
}

/// Writes `new`'s changes from `old` into `orig`. A key whose value is the same in `old` and `new` is left as
/// `orig` has it (or lacks it).
fn merge_table(orig: &mut Table, old: Option<&Table>, new: &Table) {
    // Keys the scene no longer has.
    let gone: Vec<String> = orig
        .iter()
        .map(|(k, _)| k.to_owned())
        .filter(|k| !new.contains_key(k) && old.is_some_and(|o| o.contains_key(k)))
        .collect();
    for k in gone {
        orig.remove(&k);
    }
    for (key, new_item) in new.iter() {
        let old_item = old.and_then(|o| o.get(key));
        let unchanged = old_item.is_some_and(|o| same(o, new_item));
        match orig.get_mut(key) {
            Some(item) => merge_item(item, old_item, new_item),
            None if unchanged => {}
            None => {
                let mut item = new_item.clone();
                tidy_item(&mut item);
                orig.insert(key, item);
            }
        }
    }
}

fn merge_item(orig: &mut Item, old: Option<&Item>, new: &Item) {
    match (orig, new) {
        (Item::Table(o), Item::Table(n)) => merge_table(o, old.and_then(Item::as_table), n),
        (Item::ArrayOfTables(o), Item::ArrayOfTables(n)) => {
            let old = old.and_then(Item::as_array_of_tables);
            // Source by source, by position: the first tables keep their text where unchanged.
            while o.len() > n.len() {
                o.remove(o.len() - 1);
            }
            for (i, table) in n.iter().enumerate() {
                let old_table = old.and_then(|a| a.get(i));
                match o.get_mut(i) {
                    Some(t) => merge_table(t, old_table, table),
                    None => {
                        let mut t = table.clone();
                        tidy_table(&mut t);
                        o.push(t);
                    }
                }
            }
        }
        (Item::Value(o), Item::Value(n)) => {
            let new_item = Item::Value(n.clone());
            let untouched = old.is_some_and(|old| same(old, &new_item));
            if untouched || same(&Item::Value(o.clone()), &new_item) {
                return;
            }
            let decor = o.decor().clone();
            let mut value = n.clone();
            tidy_value(&mut value);
            *value.decor_mut() = decor;
            *o = value;
        }
        (orig, new) => {
            // The same value the file writes in another form (keys as `[frame, value]` pairs, which the scene
            // writes as tables): the file's text stays.
            if old.is_some_and(|old| same(old, new)) {
                return;
            }
            let mut item = new.clone();
            tidy_item(&mut item);
            // Tables where the file has a value inline (an array of pairs in a table of an array of tables): an
            // inline array of them, which stays in its table, where new table headers would land after the file's
            // later tables and read back into the wrong one.
            if let (Item::Value(o), Item::ArrayOfTables(tables)) = (&*orig, &item) {
                let mut value = Value::Array(tables.clone().into_array());
                *value.decor_mut() = o.decor().clone();
                item = Item::Value(value);
            }
            *orig = item;
        }
    }
}

/// The same TOML value, whatever its formatting.
fn same(a: &Item, b: &Item) -> bool {
    fn plain(item: &Item) -> String {
        let mut item = item.clone();
        tidy_item(&mut item);
        match &mut item {
            Item::Value(v) => {
                v.decor_mut().clear();
                v.to_string()
            }
            other => other.to_string(),
        }
    }
    plain(a) == plain(b)
}

fn tidy_item(item: &mut Item) {
    match item {
        Item::Value(v) => tidy_value(v),
        Item::Table(t) => tidy_table(t),
        Item::ArrayOfTables(a) => {
            for t in a.iter_mut() {
                tidy_table(t);
            }
        }
        Item::None => {}
    }
}

fn tidy_table(table: &mut Table) {
    for (_, item) in table.iter_mut() {
        tidy_item(item);
    }
}

/// Arrays and inline tables on one line, or one element a line where that line would be long.
fn tidy_value(value: &mut Value) {
    match value {
        Value::Array(a) => {
            for v in a.iter_mut() {
                tidy_value(v);
            }
            one_line(a);
            if a.to_string().trim().len() > ONE_LINE {
                for v in a.iter_mut() {
                    v.decor_mut().set_prefix("\n    ");
                    v.decor_mut().set_suffix("");
                }
                a.set_trailing_comma(true);
                a.set_trailing("\n");
            }
        }
        Value::InlineTable(t) => {
            for (_, v) in t.iter_mut() {
                tidy_value(v);
            }
            t.fmt();
        }
        _ => {}
    }
}

fn one_line(a: &mut Array) {
    a.fmt();
    a.set_trailing_comma(false);
    a.set_trailing("");
}

#[cfg(test)]
mod tests {
    use super::*;

    const FILE: &str = "# A ring and a beam.\n\n[camera]\neye = [2, 4.5, 14]  # from above\ntarget = [0.0, 0.0, 0.0]\nfov_y = 34.0\n\n[colors]\nenergy = [0.3, 0.55, 1.0]\n\n# The ring.\n[[tori]]\ncenter = [0.0, 0.0, 0.0]\naxis = [1.0, 0.25, 0.0]\nmajor_radius = 1.3\ncoefficient = 3.0\n";

    fn load(text: &str) -> Scene {
        Scene::parse(text, Path::new("t.toml")).unwrap()
    }

    #[test]
    fn an_unchanged_scene_writes_its_file_back_as_it_was() {
        let saved = load(FILE);
        assert_eq!(
            update_text(FILE, &saved, &saved, Path::new("saved.toml")),
            FILE
        );
    }

    #[test]
    fn an_edit_changes_its_value_alone() {
        let saved = load(FILE);
        let mut scene = saved.clone();
        scene.sources.tori[0].major_radius = 0.97;
        scene.camera.eye.x = 3.0;
        let text = update_text(FILE, &saved, &scene, Path::new("saved.toml"));
        // The decay the file derived from its camera is written out, since the camera moved.
        let decay = format!(
            "\n[integration]\ndecay_length = {}\n",
            scene.integration.decay_length
        );
        assert_eq!(
            text,
            FILE.replace("major_radius = 1.3", "major_radius = 0.97")
                .replace("eye = [2, 4.5, 14]", "eye = [3.0, 4.5, 14.0]")
                + &decay
        );
        assert_eq!(load(&text), scene);
        // The comments stayed, the normalised axis kept its text.
        assert!(text.contains("# from above") && text.contains("axis = [1.0, 0.25, 0.0]"));
    }

    #[test]
    fn sources_added_and_removed_follow_the_file() {
        let saved = load(FILE);
        let mut scene = saved.clone();
        let mut second = scene.sources.tori[0].clone();
        second.center.y = 2.0;
        scene.sources.tori.push(second);
        scene.colors.background = [0.1, 0.2, 0.3];
        let text = update_text(FILE, &saved, &scene, Path::new("saved.toml"));
        assert_eq!(load(&text), scene);
        assert!(text.starts_with("# A ring and a beam."));
        assert_eq!(text.matches("[[tori]]").count(), 2);
        assert!(text.contains("background = [0.1, 0.2, 0.3]"), "{text}");
        let mut fewer = scene.clone();
        fewer.sources.tori.clear();
        let text = update_text(FILE, &saved, &fewer, Path::new("saved.toml"));
        assert_eq!(load(&text), fewer);
        assert!(!text.contains("[[tori]]"));
    }

    #[test]
    fn a_decay_derived_from_the_camera_is_written_once_the_camera_moves() {
        // Without decay_length the file's decay derives from its camera: moving the camera must not move it.
        let saved = load(FILE);
        let mut scene = saved.clone();
        scene.camera.eye.z = 30.0;
        let text = update_text(FILE, &saved, &scene, Path::new("saved.toml"));
        assert_eq!(load(&text), scene);
        assert!(text.contains("decay_length"));
        assert!(text.contains("# from above"));
    }

    #[test]
    fn every_shipped_scene_writes_back_as_it_was_and_an_edit_changes_one_line() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes");
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            // Scenes only (a PLY file lies beside the one that reads it).
            if path.extension().is_none_or(|e| e != "toml") {
                continue;
            }
            let text = std::fs::read_to_string(&path).unwrap();
            let saved = Scene::parse(&text, &path).unwrap();
            assert_eq!(
                update_text(&text, &saved, &saved, &path),
                text,
                "{}",
                path.display()
            );
            let mut scene = saved.clone();
            let c = match (
                scene.sources.tori.first_mut(),
                scene.sources.curves.first_mut(),
            ) {
                (Some(t), _) => &mut t.coefficient,
                (None, Some(c)) => &mut c.coefficient,
                _ => continue,
            };
            *c = 2.75;
            let edited = update_text(&text, &saved, &scene, &path);
            assert_eq!(load(&edited), scene, "{}", path.display());
            let changed = text
                .lines()
                .zip(edited.lines())
                .filter(|(a, b)| a != b)
                .count();
            assert_eq!(changed, 1, "{}:\n{edited}", path.display());
            assert_eq!(text.lines().count(), edited.lines().count());
        }
    }

    #[test]
    fn keys_written_as_pairs_stay_in_their_track_when_one_changes() {
        let text = "[[tori]]\ncenter = [0.0, 0.0, 0.0]\naxis = [0.0, 1.0, 0.0]\nmajor_radius = 1.0\ncoefficient = 1.0\n\n\
                    [animation]\nframes = 100\n\n[[animation.tracks]]\nparameter = \"tori[0].major_radius\"\n\
                    keys = [[0, 0.5], [90, 3.0]]  # swells\n\n[[animation.tracks]]\nparameter = \"tori[0].coefficient\"\n\
                    keys = [[0, 2.5], [70, 1.5]]\n";
        let path = Path::new("pairs.toml");
        let saved = Scene::parse(text, path).unwrap();
        assert_eq!(update_text(text, &saved, &saved, path), text);
        let mut scene = saved.clone();
        scene.animation.as_mut().unwrap().tracks[0].keys[1].value =
            crate::animation::Value::Number(4.0);
        let edited = update_text(text, &saved, &scene, path);
        assert_eq!(load(&edited), scene, "{edited}");
        // Only the edited track's keys line changed, still inside its own track, with its comment.
        let changed: Vec<(&str, &str)> = (text.lines().zip(edited.lines()))
            .filter(|(a, b)| a != b)
            .collect();
        assert_eq!(changed.len(), 1, "{edited}");
        assert!(
            changed[0].1.contains("4.0") && changed[0].1.contains("# swells"),
            "{edited}"
        );
    }

    #[test]
    fn fresh_text_puts_small_arrays_on_one_line_and_numbers_short() {
        let mut scene = Scene::default_scene();
        scene.sources.tori[0].major_radius = 0.97;
        let text = fresh_text(&scene, Path::new("saved.toml"));
        assert_eq!(load(&text), scene);
        assert!(text.contains("eye = [2.0, 4.5, 14.0]\n"), "{text}");
        assert!(text.contains("major_radius = 0.97\n"));
        // No number alone on its line.
        assert!(
            !text
                .lines()
                .any(|l| l.trim().trim_end_matches(',').parse::<f64>().is_ok()),
            "{text}"
        );
    }
}
