//! Particle sets as scene files give them: emitters placed by shape around the scene's sources, PLY files in
//! every encoding read to the same particles, saving and loading again lossless, and every bad input (a missing,
//! truncated, wrongly ordered or positionless PLY, a negative radius or density, too many particles) refused
//! with its file, place and field named, exit status 2 and nothing written.

mod common;

use std::path::{Path, PathBuf};

use energywave::particles::{Origin, gather};
use energywave::scene::Scene;
use glam::DVec3;

fn tmpdir(name: &str) -> PathBuf {
    common::tmpdir("particle_files", name)
}

fn parse(text: &str, dir: &Path) -> Result<Scene, String> {
    Scene::parse(text, &dir.join("scene.toml")).map_err(|e| e.to_string())
}

/// The particles of a PLY file of three vertices, each with position, radius, density and color, in `format`
/// (`ascii`, `binary_little_endian`, `binary_big_endian`); with `lie`, a binary file's header names the other
/// byte order than its data has.
fn ply(format: &str, lie: bool) -> Vec<u8> {
    let vertices = [
        ([0.5f32, -1.0, 2.0], 0.25f32, 3.0f32, [255u8, 128, 0]),
        ([1.5, 0.0, -2.0], 0.5, 1.0, [0, 0, 255]),
        ([-3.0, 2.5, 0.125], 0.125, 0.0, [10, 20, 30]),
    ];
    let declared = match (format, lie) {
        ("binary_little_endian", true) => "binary_big_endian",
        ("binary_big_endian", true) => "binary_little_endian",
        (f, _) => f,
    };
    let mut out = format!(
        "ply\nformat {declared} 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
         property float radius\nproperty float density\nproperty uchar red\nproperty uchar green\n\
         property uchar blue\nend_header\n"
    )
    .into_bytes();
    for (p, r, d, c) in vertices {
        if format == "ascii" {
            out.extend(
                format!(
                    "{} {} {} {r} {d} {} {} {}\n",
                    p[0], p[1], p[2], c[0], c[1], c[2]
                )
                .bytes(),
            );
            continue;
        }
        for x in [p[0], p[1], p[2], r, d] {
            out.extend(match format {
                "binary_little_endian" => x.to_le_bytes(),
                _ => x.to_be_bytes(),
            });
        }
        out.extend(c);
    }
    out
}

fn with_file(dir: &Path, bytes: &[u8]) -> Result<Scene, String> {
    std::fs::write(dir.join("cloud.ply"), bytes).unwrap();
    parse(
        "[[points]]\nposition = [0, 0, 0]\ncoefficient = 1\n\n[[particles]]\nfile = \"cloud.ply\"\n",
        dir,
    )
}

#[test]
fn every_ply_encoding_gives_the_same_particles() {
    let dir = tmpdir("encodings");
    let sets: Vec<_> = ["ascii", "binary_little_endian", "binary_big_endian"]
        .iter()
        .map(|f| {
            let scene = with_file(&dir, &ply(f, false)).unwrap();
            match &scene.particles[0].origin {
                Origin::File { particles, .. } => particles.as_ref().clone(),
                _ => unreachable!(),
            }
        })
        .collect();
    assert_eq!(sets[0], sets[1]);
    assert_eq!(sets[0], sets[2]);
    let p = &sets[0];
    assert_eq!(p.len(), 3);
    assert_eq!(p[0].position, DVec3::new(0.5, -1.0, 2.0));
    assert_eq!((p[1].radius, p[1].density), (0.5, 1.0));
    assert_eq!(p[0].color, [1.0, 128.0 / 255.0, 0.0]);
    assert_eq!(p[2].density, 0.0);
}

#[test]
fn a_file_without_radius_density_or_color_takes_the_sets_own() {
    let dir = tmpdir("defaults");
    std::fs::write(
        dir.join("bare.ply"),
        "ply\nformat ascii 1.0\nelement vertex 2\nproperty double x\nproperty double y\nproperty double z\n\
         end_header\n0 0 0\n1 2 3\n",
    )
    .unwrap();
    let scene = parse(
        "[[points]]\nposition = [0, 0, 0]\ncoefficient = 1\n\n[[particles]]\nfile = \"bare.ply\"\n\
         particle_radius = 0.3\ndensity = 2.5\ncolor = [0.1, 0.2, 0.3]\nalbedo = 0.5\n",
        &dir,
    )
    .unwrap();
    let p = gather(&scene.particles, &scene.sources);
    assert_eq!(p.len(), 2);
    assert_eq!(p[1].position, DVec3::new(1.0, 2.0, 3.0));
    assert_eq!((p[1].radius, p[1].density), (0.3, 2.5));
    // The renderers take the color times the set's albedo.
    assert_eq!(p[0].color, [0.05, 0.1, 0.15]);
}

#[test]
fn emitters_follow_the_sources_they_name() {
    let dir = tmpdir("emitters");
    let scene = parse(
        r#"
[[tori]]
center = [1.0, 2.0, 3.0]
axis = [0.0, 1.0, 1.0]
major_radius = 2.0
coefficient = 1.0

[[curves]]
control_points = [[-2, 0, 0], [0, 2, 0], [2, 0, 0]]
coefficient = 1.0

[[particles]]
emitter = "torus"
torus = 0
spread = 0.3
count = 500

[[particles]]
emitter = "curve"
curve = 0
spread = 0.2
count = 500
particle_radius = [0.05, 0.1]
density = [1, 2]

[[particles]]
emitter = "box"
center = [0, -5, 0]
size = [2, 1, 4]
count = 300
"#,
        &dir,
    )
    .unwrap();
    let torus = &scene.sources.tori[0];
    let curve = &scene.sources.curves[0].control_points;
    let sets: Vec<_> = (scene.particles.iter())
        .map(|s| s.particles(&scene.sources))
        .collect();
    assert_eq!(
        sets.iter().map(Vec::len).collect::<Vec<_>>(),
        [500, 500, 300]
    );
    for p in &sets[0] {
        let d = energywave::field::torus_distance(p.position, torus.center, torus.axis, 2.0);
        assert!(d <= 0.3 + 1e-12, "{d}");
    }
    // The chain is one quadratic segment: its nearest point by the field's own search.
    for p in &sets[1] {
        let d = energywave::field::curve::nearest_on_chain(curve, p.position).distance;
        assert!(d <= 0.2 + 1e-12, "{d}");
        assert!((0.05..=0.1).contains(&p.radius) && (1.0..=2.0).contains(&p.density));
    }
    for p in &sets[2] {
        let q = p.position - DVec3::new(0.0, -5.0, 0.0);
        assert!(q.abs().cmple(DVec3::new(1.0, 0.5, 2.0)).all(), "{q}");
    }
    // Spread over what they name, not gathered at one place that the bounds above would let through: around the
    // whole ring, along the whole chain, into every corner of the box, through the spread's depth, and their radii and
    // densities over their ranges.
    let share = |set: &[energywave::particles::Particle],
                 f: &dyn Fn(&energywave::particles::Particle) -> bool| {
        set.iter().filter(|p| f(p)).count() as f64 / set.len() as f64
    };
    let frame = torus.axis.any_orthonormal_pair();
    for quarter in 0..4 {
        let s = share(&sets[0], &|p| {
            let q = p.position - torus.center;
            let a = q
                .dot(frame.1)
                .atan2(q.dot(frame.0))
                .rem_euclid(std::f64::consts::TAU);
            (a / std::f64::consts::FRAC_PI_2) as usize == quarter
        });
        assert!(
            (0.15..0.35).contains(&s),
            "torus: {s} of the set in quarter {quarter} of the ring"
        );
    }
    let deep = share(&sets[0], &|p| {
        energywave::field::torus_distance(p.position, torus.center, torus.axis, 2.0) > 0.15
    });
    assert!(
        deep > 0.3,
        "torus: {deep} of the set deeper than half the spread"
    );
    for quarter in 0..4 {
        let s = share(&sets[1], &|p| {
            let t = energywave::field::curve::nearest_on_chain(curve, p.position).t;
            ((t * 4.0) as usize).min(3) == quarter
        });
        assert!(
            s > 0.1,
            "curve: {s} of the set along quarter {quarter} of the chain"
        );
    }
    let (r, d): (Vec<f64>, Vec<f64>) = sets[1].iter().map(|p| (p.radius, p.density)).unzip();
    let span = |v: &[f64]| {
        v.iter().copied().fold(f64::MIN, f64::max) - v.iter().copied().fold(f64::MAX, f64::min)
    };
    assert!(
        span(&r) > 0.04 && span(&d) > 0.8,
        "radii span {}, densities {}",
        span(&r),
        span(&d)
    );
    for octant in 0..8 {
        let s = share(&sets[2], &|p| {
            let q = p.position - DVec3::new(0.0, -5.0, 0.0);
            (q.x > 0.0) as usize + 2 * (q.y > 0.0) as usize + 4 * (q.z > 0.0) as usize == octant
        });
        assert!(
            (0.05..0.2).contains(&s),
            "box: {s} of the set in octant {octant}"
        );
    }
    // Moving the curve moves its sparks.
    let mut moved = scene.clone();
    moved.sources.curves[0].control_points[1].y = 4.0;
    assert_ne!(moved.particles[1].particles(&moved.sources), sets[1]);
}

#[test]
fn saving_and_loading_again_gives_the_same_sets() {
    let dir = tmpdir("round_trip");
    std::fs::write(dir.join("cloud.ply"), ply("ascii", false)).unwrap();
    let text = r#"
[[curves]]
control_points = [[-2, 0, 0], [0, 2, 0], [2, 0, 0]]
coefficient = 1.0

[slices]
width = 0.25

[[particles]]
emitter = "curve"
curve = 0
count = 40
particle_radius = [0.05, 0.1]
density = 3.0
color = [0.5, 0.4, 0.3]
seed = 9
noise = 0.25
albedo = 0.7
emission = [1.0, 0.4, 0.1]
emission_intensity = 2.5

[[particles]]
file = "cloud.ply"
emission = [0.2, 0.5, 1.0]
"#;
    let scene = parse(text, &dir).unwrap();
    assert_eq!(scene.slice_width, 0.25);
    // A color alone glows at intensity 1; a set without either glows with none.
    assert_eq!(scene.particles[0].emission.intensity, 2.5);
    assert_eq!(scene.particles[1].emission.color, [0.2, 0.5, 1.0]);
    assert_eq!(scene.particles[1].emission.intensity, 1.0);
    let again = parse(&scene.to_toml(), &dir).unwrap();
    assert_eq!(scene, again);
}

/// The scene's problems, one message.
fn refused(text: &str, dir: &Path) -> String {
    match parse(text, dir) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e,
    }
}

#[test]
fn bad_particle_sets_are_refused_with_their_place() {
    let dir = tmpdir("bad");
    let source = "[[points]]\nposition = [0, 0, 0]\ncoefficient = 1\n\n";
    for (set, phrase) in [
        ("file = \"nowhere.ply\"", "particles[0].file: "),
        (
            "emitter = \"sphere\"\ncount = 10\nparticle_radius = -0.1",
            "particles[0].particle_radius: [-0.1, -0.1]",
        ),
        (
            "emitter = \"sphere\"\ncount = 10\ndensity = [2, -1]",
            "particles[0].density: [2, -1]",
        ),
        (
            "emitter = \"sphere\"\ncount = 10\ndensity = [3, 1]",
            "first number at most its second",
        ),
        (
            "emitter = \"sphere\"\ncount = 1000001",
            "a scene takes 0 to 1000000 particles",
        ),
        (
            "emitter = \"curve\"\ncurve = 2\ncount = 10",
            "curve 2: the scene has 0 curve sources",
        ),
        (
            "emitter = \"cone\"\ncount = 10",
            "\"cone\" is not an emitter",
        ),
        (
            "emitter = \"torus\"\ncount = 10\nradius = 2",
            "particles[0].radius: a torus emitter has no radius",
        ),
        ("emitter = \"sphere\"", "an emitter needs its count"),
        ("count = 5", "a file (a PLY point cloud) or an emitter"),
        (
            "file = \"x.ply\"\nemitter = \"box\"",
            "a file or an emitter, not both",
        ),
        (
            "emitter = \"sphere\"\ncount = 10\nalbedo = 1.5",
            "an albedo is a share of the light",
        ),
        (
            "emitter = \"sphere\"\ncount = 10\nemission = [1.5, 0, 0]",
            "particles[0].emission: ",
        ),
        (
            "emitter = \"sphere\"\ncount = 10\nemission_intensity = 1e4",
            "particles[0].emission_intensity: 10000 is out of range",
        ),
        (
            "emitter = \"sphere\"\ncount = 10\nnoise = -1",
            "the noise is in 0..1",
        ),
    ] {
        let e = refused(&format!("{source}[[particles]]\n{set}\n"), &dir);
        assert!(
            e.contains("scene.toml:") && e.contains(phrase),
            "{set}: {e}"
        );
    }
    let e = refused(&format!("{source}[slices]\nwidth = 0\n"), &dir);
    assert!(e.contains("slices.width") && e.contains("0.05..2"), "{e}");
    // Two sets of 600 000 each: the limit is the scene's.
    let e = refused(
        &format!(
            "{source}[[particles]]\nemitter = \"sphere\"\ncount = 600000\n\n[[particles]]\nemitter = \"box\"\ncount = 600000\n"
        ),
        &dir,
    );
    assert!(e.contains("1200000 particles in all"), "{e}");
}

#[test]
fn bad_ply_files_are_refused_with_what_is_wrong() {
    let dir = tmpdir("bad_ply");
    let check = |bytes: &[u8], phrase: &str| {
        let e = with_file(&dir, bytes).expect_err("a bad PLY is refused");
        assert!(
            e.contains("particles[0].file") && e.contains("cloud.ply") && e.contains(phrase),
            "{phrase}: {e}"
        );
    };
    // Cut short: the header promises three vertices, the data holds two and a half.
    let whole = ply("binary_little_endian", false);
    check(&whole[..whole.len() - 20], "cut short");
    // Binary little-endian data under a big-endian header, and the other way round.
    check(&ply("binary_little_endian", true), "byte order");
    check(&ply("binary_big_endian", true), "byte order");
    // No positions.
    check(
        b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n1 2\n",
        "no z",
    );
    check(
        b"ply\nformat ascii 1.0\nelement face 0\nend_header\n",
        "no vertex element",
    );
    check(b"solid cube\nfacet normal 0 0 1\n", "not a PLY file");
    check(
        b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n\
          property float radius\nend_header\n0 0 0 -0.5\n",
        "vertex 0: radius -0.5 must be positive",
    );
    check(
        b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n\
          property float density\nend_header\n0 0 0 -2\n",
        "vertex 0: density -2 must be at least 0",
    );
    // A million and one vertices: refused from the header, before any is read.
    check(
        b"ply\nformat binary_little_endian 1.0\nelement vertex 1000001\nproperty float x\nproperty float y\n\
          property float z\nend_header\n",
        "a scene takes at most 1000000 particles",
    );
}

#[test]
fn the_command_line_refuses_a_bad_ply_with_status_2_and_writes_nothing() {
    let dir = tmpdir("cli");
    let whole = ply("binary_big_endian", false);
    std::fs::write(dir.join("cloud.ply"), &whole[..whole.len() - 7]).unwrap();
    let scene = dir.join("scene.toml");
    std::fs::write(
        &scene,
        "[[points]]\nposition = [0, 0, 0]\ncoefficient = 1\n\n[[particles]]\nfile = \"cloud.ply\"\n",
    )
    .unwrap();
    let e = common::render_refused(&scene, &dir.join("out.png"));
    assert!(
        e.contains("scene.toml:6:") && e.contains("particles[0].file") && e.contains("cut short"),
        "{e}"
    );
}
