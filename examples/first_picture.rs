//! How long the viewer takes to its first picture, scene by scene: the scene read, the GPU device made, the
//! viewer's GPU side and app made, then its first frames drawn offscreen (each waited for on the GPU), through
//! the window's own frame code at 1280 x 800. Prints one line a scene and, with `--json FILE`, writes them.
//!
//!   cargo run --release --example first_picture -- assets/scenes/*.toml default
//!
//! `default` is the embedded default scene. The first run on a machine also fills Mesa's shader cache (lavapipe
//! compiles a pipeline at its first dispatch); runs after it find the cache warm, as a user's second start does.

use std::time::Instant;

use energywave::scene::Scene;
use energywave::viewer::Document;
use energywave::viewer::offscreen::OffscreenViewer;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let json = match args.iter().position(|a| a == "--json") {
        Some(i) => {
            let path = args.get(i + 1).cloned().ok_or("--json needs a file")?;
            args.drain(i..i + 2);
            Some(path)
        }
        None => None,
    };
    let mut rows = Vec::new();
    println!(
        "scene: to the first picture (read, device and viewer, first frame) | second frame | what was still being prepared"
    );
    for path in &args {
        let start = Instant::now();
        let scene = match path.as_str() {
            "default" => Scene::default_scene(),
            p => Scene::load(std::path::Path::new(p))?,
        };
        let read = start.elapsed().as_secs_f64();
        let mut v = OffscreenViewer::new(Document::new(scene, None), 1280, 800)?;
        let made = start.elapsed().as_secs_f64();
        v.frame()?;
        let first = start.elapsed().as_secs_f64();
        let preparing = v.app.report().preparing;
        let second_start = Instant::now();
        v.frame()?;
        let second = second_start.elapsed().as_secs_f64();
        println!(
            "{path}: {:.0} ms ({:.0} + {:.0} + {:.0}) | {:.0} ms | {}",
            first * 1e3,
            read * 1e3,
            (made - read) * 1e3,
            (first - made) * 1e3,
            second * 1e3,
            preparing.as_deref().unwrap_or("-")
        );
        rows.push(serde_json::json!({
            "scene": path,
            "first_picture_ms": first * 1e3,
            "read_ms": read * 1e3,
            "device_and_viewer_ms": (made - read) * 1e3,
            "first_frame_ms": (first - made) * 1e3,
            "second_frame_ms": second * 1e3,
            "preparing": preparing,
        }));
    }
    if let Some(path) = json {
        std::fs::write(path, serde_json::to_string_pretty(&rows)? + "\n")?;
    }
    Ok(())
}
