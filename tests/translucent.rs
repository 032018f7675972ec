//! Translucent objects (METHOD.md section 11): the voxel number map and its table against closed forms and a
//! brute-force f64 reference (converging as the voxels shrink), the Fresnel equations, energy, a cavity against
//! the depth-map estimate, and bad input. The f64 reference shares the model's code (`light_at`,
//! `Medium::optical_thickness`); what shares none is the sphere's closed form (`sphere_oracle`: a sphere lit from
//! outside, its chords and spread in closed form, the Fresnel equations written apart), which both the reference
//! and the table meet, and the closed-form transmittance through a sphere.

mod common;

use std::sync::Arc;

use energywave::frame::FrameCache;
use energywave::objects::lighting::Lights;
use energywave::objects::mesh::MeshData;
use energywave::objects::translucent::light::{
    Irradiance, Prepared, Scattered, irradiance, leaving,
};
use energywave::objects::translucent::reference::{Estimate, Reference};
use energywave::objects::translucent::table::{Table, thickness};
use energywave::objects::translucent::voxels::Voxels;
use energywave::objects::translucent::{
    Inner, InnerShape, Medium, Translucent, fresnel_transmittance,
};
use energywave::objects::{MeshObject, Object, Shape};
use energywave::scene::Scene;
use glam::DVec3;

thread_local! {
    /// The voxels and tables this test thread made, kept as a renderer's frame cache keeps them.
    static CACHE: FrameCache = FrameCache::new();
}

/// `object`'s voxels and table (`translucent::light::prepare`), through the thread's frame cache.
fn prepared(object: &Object) -> Option<Arc<Prepared>> {
    CACHE.with(|c| c.translucent_here(object))
}

fn scene(name: &str) -> Scene {
    Scene::load(std::path::Path::new(&format!("assets/scenes/{name}.toml")))
        .expect("the preset loads")
}

fn material(extinction: f64, resolution: u32) -> Option<Box<Translucent>> {
    Some(Box::new(Translucent {
        extinction,
        eta: 1.4,
        inner: None,
        noise: None,
        resolution: Some(resolution),
    }))
}

/// The poster's cube (side 1.2) with a clear spherical cavity of radius 0.4 at its center.
fn cavity_cube(extinction: f64, resolution: u32) -> Object {
    let mut m = material(extinction, resolution).unwrap();
    m.inner = Some(Inner {
        shape: InnerShape::Sphere {
            center: DVec3::ZERO,
            radius: 0.4,
        },
        extinction: 0.0,
    });
    Object {
        shape: Shape::Box {
            center: DVec3::ZERO,
            size: DVec3::splat(1.2),
            rotation: DVec3::ZERO,
        },
        color: [1.0; 3],
        translucent: Some(m),
    }
}

fn sphere(extinction: f64, resolution: u32) -> Object {
    Object {
        shape: Shape::Sphere {
            center: DVec3::new(0.1, -0.2, 0.3),
            radius: 0.7,
        },
        color: [1.0; 3],
        translucent: material(extinction, resolution),
    }
}

/// A closed L-shaped prism (not convex): the outline (0,0) (2,0) (2,1) (1,1) (1,2) (0,2) (0,1), z from 0 to 1,
/// every triangle wound counter-clockwise seen from outside, centered at the origin.
fn l_prism(extinction: f64, resolution: u32) -> Object {
    let outline = [
        (0.0, 0.0),
        (2.0, 0.0),
        (2.0, 1.0),
        (1.0, 1.0),
        (1.0, 2.0),
        (0.0, 2.0),
        (0.0, 1.0),
    ];
    let c = DVec3::new(0.8, 0.8, 0.5);
    let p = |(x, y): (f64, f64), z: f64| DVec3::new(x, y, z) - c;
    let mut triangles = Vec::new();
    // The caps: the lower rectangle as a fan from (0,0) through (2,0) (2,1) (1,1) (0,1), the upper square apart.
    let caps = [
        [(0.0, 0.0), (2.0, 0.0), (2.0, 1.0)],
        [(0.0, 0.0), (2.0, 1.0), (1.0, 1.0)],
        [(0.0, 0.0), (1.0, 1.0), (0.0, 1.0)],
        [(0.0, 1.0), (1.0, 1.0), (1.0, 2.0)],
        [(0.0, 1.0), (1.0, 2.0), (0.0, 2.0)],
    ];
    for t in caps {
        triangles.push([p(t[0], 1.0), p(t[1], 1.0), p(t[2], 1.0)]);
        triangles.push([p(t[0], 0.0), p(t[2], 0.0), p(t[1], 0.0)]);
    }
    for k in 0..outline.len() {
        let (a, b) = (outline[k], outline[(k + 1) % outline.len()]);
        triangles.push([p(a, 0.0), p(b, 0.0), p(b, 1.0)]);
        triangles.push([p(a, 0.0), p(b, 1.0), p(a, 1.0)]);
    }
    let data = MeshData::new(triangles);
    assert_eq!(data.open_edges(), 0, "the prism is closed");
    Object {
        shape: Shape::Mesh(MeshObject {
            path: "l_prism.glb".into(),
            translation: DVec3::ZERO,
            rotation: DVec3::ZERO,
            scale: DVec3::ONE,
            data: Arc::new(data),
        }),
        color: [1.0; 3],
        translucent: material(extinction, resolution),
    }
}

/// The poster's light: a ring beside the object's -x face.
fn ring_scene(object: Object) -> Scene {
    let mut s = scene("translucent_cavity");
    s.objects = vec![object];
    s
}

fn lights(s: &Scene) -> Lights {
    Lights::new(&s.sources, s.colors.palette(), s.integration.epsilon)
}

#[test]
fn optical_thickness_matches_closed_forms() {
    let sigma = 1.7;
    // A uniform slab: through a box's opposite faces, a slanted path's length.
    let slab = Object {
        shape: Shape::Box {
            center: DVec3::ZERO,
            size: DVec3::new(1.0, 0.5, 1.0),
            rotation: DVec3::ZERO,
        },
        color: [1.0; 3],
        translucent: material(sigma, 32),
    };
    let m = Medium::of(&slab).unwrap();
    let (a, b) = (DVec3::new(-0.3, -0.25, 0.1), DVec3::new(0.2, 0.25, -0.2));
    let exact = sigma * (b - a).length();
    assert!((m.optical_thickness(a, b, 1) - exact).abs() < 1e-12 * exact);
    // Beyond the slab the path gathers nothing: the same from outside to outside.
    let (a2, b2) = (a + (a - b) * 2.0, b + (b - a) * 3.0);
    assert!((m.optical_thickness(a2, b2, 1) - exact).abs() < 1e-9 * exact);
    // A sphere's chord: 2 sqrt(r^2 - d^2) at distance d from the center.
    let ball = sphere(sigma, 32);
    let m = Medium::of(&ball).unwrap();
    let center = DVec3::new(0.1, -0.2, 0.3);
    for d in [0.0, 0.3, 0.6, 0.69] {
        let from = center + DVec3::new(-5.0, d, 0.0);
        let to = center + DVec3::new(5.0, d, 0.0);
        let chord = 2.0 * (0.49f64 - d * d).sqrt();
        let tau = m.optical_thickness(from, to, 1);
        assert!((tau - sigma * chord).abs() < 1e-9, "chord at {d}: {tau}");
    }
    // Through the cavity, where sigma_t = 0: the cube's 1.2 less the cavity's 0.8.
    let cube = cavity_cube(sigma, 32);
    let m = Medium::of(&cube).unwrap();
    let tau = m.optical_thickness(DVec3::new(-1.0, 0.0, 0.0), DVec3::new(1.0, 0.0, 0.0), 1);
    assert!((tau - sigma * 0.4).abs() < 1e-9, "{tau}");
    // Off the cavity's axis, at height h: 1.2 - 2 sqrt(0.16 - h^2).
    let h = 0.25;
    let tau = m.optical_thickness(DVec3::new(-1.0, h, 0.0), DVec3::new(1.0, h, 0.0), 1);
    assert!((tau - sigma * (1.2 - 2.0 * (0.16f64 - h * h).sqrt())).abs() < 1e-9);

    // The voxels' thickness converges to the same values as the voxels shrink: the mean error over segments
    // between points spread over the cube's faces (a single segment's error is not monotone: one grazing the
    // cavity crosses its staircase of voxels for a long way at some resolutions and not at others).
    let points: Vec<DVec3> = (0..64)
        .map(|k| {
            let u = |j: u32| ((k as f64 + 0.5) * (0.618_034 * j as f64 + 0.1)).fract() - 0.5;
            let axis = k % 3;
            let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
            let mut p = DVec3::new(u(1), u(2), u(3)) * 1.2;
            p[axis] = 0.6 * sign;
            p
        })
        .collect();
    let mut last = f64::INFINITY;
    for resolution in [12, 24, 48] {
        let v = Voxels::of(&cavity_cube(sigma, resolution), resolution).unwrap();
        let mut sum = 0.0;
        let mut count = 0;
        for (k, &from) in points.iter().enumerate() {
            for &to in &points[k + 1..] {
                sum += (thickness(&v, from, to) - m.optical_thickness(from, to, 1)).abs();
                count += 1;
            }
        }
        let mean = sum / count as f64;
        println!("resolution {resolution}: mean |tau - exact| {mean:.5}");
        assert!(
            mean < last * 0.75,
            "the voxels' error shrinks: {mean} after {last}"
        );
        last = mean;
    }
    assert!(last < 0.01 * sigma, "{last}");
}

#[test]
fn fresnel_transmittance_matches_the_fresnel_equations() {
    for eta in [1.0f64 / 1.5, 1.31, 1.5, 2.4] {
        // Head on: 1 - ((eta - 1) / (eta + 1))^2.
        let r0 = ((eta - 1.0) / (eta + 1.0)).powi(2);
        assert!((fresnel_transmittance(eta, 1.0) - (1.0 - r0)).abs() < 1e-12);
        // Every angle: the sine and tangent forms, rs = -sin(i - t) / sin(i + t), rp = tan(i - t) / tan(i + t).
        for k in 1..90 {
            let i = (k as f64).to_radians();
            let sin_t = i.sin() / eta;
            let ft = fresnel_transmittance(eta, i.cos());
            if sin_t >= 1.0 {
                assert_eq!(
                    ft, 0.0,
                    "total internal reflection at {k} degrees, eta {eta}"
                );
                continue;
            }
            let t = sin_t.asin();
            let rs = -(i - t).sin() / (i + t).sin();
            let rp = (i - t).tan() / (i + t).tan();
            let expected = 1.0 - 0.5 * (rs * rs + rp * rp);
            assert!(
                (ft - expected).abs() < 1e-12,
                "{k} degrees, eta {eta}: {ft} against {expected}"
            );
        }
        // At Brewster's angle the p wave passes whole: F_r = rs^2 / 2.
        if eta > 1.0 {
            let b = eta.atan();
            let t = (b.sin() / eta).asin();
            let rs = (b - t).sin() / (b + t).sin();
            assert!((fresnel_transmittance(eta, b.cos()) - (1.0 - 0.5 * rs * rs)).abs() < 1e-12);
        }
        // Grazing: nothing enters.
        assert!(fresnel_transmittance(eta, 0.0) < 1e-12);
    }
}

/// The light leaving every surface voxel, its power: `sum_l A_l pi S_l` (before the exit's Fresnel, which lets
/// out less), against what enters, `sum_k E_k A_k`.
fn powers(object: &Object) -> (f64, f64) {
    let s = ring_scene(object.clone());
    let lights = lights(&s);
    let p = prepared(object).unwrap();
    let medium = Medium::of(object).unwrap();
    let light = irradiance(&medium, &p.voxels, &lights, &s.objects);
    let out = leaving(&p, &light);
    let area = |k: usize| p.voxels.surface[k].area;
    let entering: f64 = (0..out.len()).map(|k| light.entering[k][0] * area(k)).sum();
    let leaving: f64 = (0..out.len())
        .map(|l| out[l][0] * area(l) * std::f64::consts::PI)
        .sum();
    (entering, leaving)
}

/// What enters leaves: this holds for any table by construction (each voxel's light is divided by its own spread),
/// so it checks the sums' indexing, not the table's values; `a_sphere_lit_from_outside_scatters_as_its_closed_form`
/// checks those.
#[test]
fn no_more_light_leaves_than_enters() {
    for extinction in [0.0, 0.5, 3.0, 30.0] {
        let (entering, leaving) = powers(&cavity_cube(extinction, 12));
        println!("extinction {extinction}: entering {entering:.5}, leaving {leaving:.5}");
        assert!(entering > 0.1);
        // All of it leaves (the inside does not absorb; the tint does), and never more.
        assert!(leaving <= entering * (1.0 + 1e-9));
        assert!(leaving >= entering * (1.0 - 1e-9));
    }
    // Through the exit's Fresnel, less: its hemispherical mean is below 1.
    let (eta, n): (f64, usize) = (1.4, 2000);
    let mean: f64 = (0..n)
        .map(|k| {
            // cos^2 uniform in [0, 1]: the cosine-weighted hemisphere.
            let c = ((k as f64 + 0.5) / n as f64).sqrt();
            fresnel_transmittance(eta, c)
        })
        .sum::<f64>()
        / n as f64;
    assert!(mean < 1.0 && mean > 0.8, "{mean}");
}

/// The table's light at points of the object's drawn surface against the reference's, relative RMS over the
/// points.
fn error_against_reference(
    object: &Object,
    reference: &Reference<'_>,
    points: &[(DVec3, DVec3)],
) -> f64 {
    let s = ring_scene(object.clone());
    let lights = lights(&s);
    let scattered = Scattered::of(object, prepared(object).unwrap(), &lights, &s.objects).unwrap();
    let mut num = 0.0;
    let mut den = 0.0;
    for &(x, n) in points {
        let got = scattered.at(x, n)[0];
        let want = reference.leaving(x, n, Estimate::Exact)[0];
        num += (got - want).powi(2);
        den += want * want;
    }
    (num / den).sqrt()
}

/// Points of a box's faces (side 1.2 around the origin), away from its edges, with their normals.
fn cube_points() -> Vec<(DVec3, DVec3)> {
    let mut out = Vec::new();
    for axis in 0..3 {
        for sign in [-1.0, 1.0] {
            let n = DVec3::AXES[axis] * sign;
            let (u, v) = (DVec3::AXES[(axis + 1) % 3], DVec3::AXES[(axis + 2) % 3]);
            for (a, b) in [(0.0, 0.0), (0.3, -0.2), (-0.35, 0.35), (0.4, 0.1)] {
                out.push((n * 0.6 + u * a + v * b, n));
            }
        }
    }
    out
}

#[test]
fn the_table_converges_to_the_reference_on_the_posters_cube() {
    let extinction = 1.5;
    let fine = cavity_cube(extinction, 8);
    let s = ring_scene(fine.clone());
    let lights = lights(&s);
    let reference = Reference::new(&fine, &s.objects, &lights, 0.06);
    let points = cube_points();
    let mut errors = Vec::new();
    for resolution in [8, 12, 16, 24] {
        let e = error_against_reference(&cavity_cube(extinction, resolution), &reference, &points);
        println!("cube with a cavity, {resolution}^3: relative RMS error {e:.4}");
        errors.push(e);
    }
    assert!(errors.windows(2).all(|w| w[1] < w[0]), "{errors:?}");
    assert!(errors[errors.len() - 1] < 0.01, "{errors:?}");
}

#[test]
fn the_table_converges_to_the_reference_on_a_concave_mesh() {
    let extinction = 1.0;
    let base = l_prism(extinction, 8);
    let s = ring_scene(base.clone());
    let lights = lights(&s);
    let reference = Reference::new(&base, &s.objects, &lights, 0.1);
    // Points on the prism's faces: the caps, the outer sides and the sides of the inner corner, which see each
    // other across the outside (light carried between them only through the inside).
    let c = DVec3::new(0.8, 0.8, 0.5);
    let at = |x: f64, y: f64, z: f64| DVec3::new(x, y, z) - c;
    let points = vec![
        (at(0.5, 0.5, 1.0), DVec3::Z),
        (at(1.5, 0.5, 1.0), DVec3::Z),
        (at(0.5, 1.5, 1.0), DVec3::Z),
        (at(0.5, 0.5, 0.0), -DVec3::Z),
        (at(1.5, 0.4, 0.0), -DVec3::Z),
        (at(2.0, 0.5, 0.5), DVec3::X),
        (at(1.0, 1.5, 0.5), DVec3::X),
        (at(1.5, 1.0, 0.5), DVec3::Y),
        (at(0.5, 2.0, 0.5), DVec3::Y),
        (at(0.0, 0.5, 0.5), -DVec3::X),
        (at(0.0, 1.5, 0.5), -DVec3::X),
        (at(1.0, 0.0, 0.5), -DVec3::Y),
    ];
    let mut errors = Vec::new();
    for resolution in [8, 12, 16, 24] {
        let e = error_against_reference(&l_prism(extinction, resolution), &reference, &points);
        println!("L-shaped prism, {resolution} a side: relative RMS error {e:.4}");
        errors.push(e);
    }
    assert!(errors.windows(2).all(|w| w[1] < w[0]), "{errors:?}");
    assert!(errors[errors.len() - 1] < 0.05, "{errors:?}");
}

#[test]
fn the_cavity_lets_light_through_where_a_depth_map_sees_a_solid_cube() {
    // The ring lights the -x face; on the far face (+x) the point behind the cavity gets the light that crossed
    // it, the corner beside it light that crossed the solid cube.
    let extinction = 3.0;
    let cube = cavity_cube(extinction, 24);
    let s = ring_scene(cube.clone());
    let lights = lights(&s);
    let reference = Reference::new(&cube, &s.objects, &lights, 0.06);
    let behind = (DVec3::new(0.6, 0.0, 0.0), DVec3::X);
    let beside = (DVec3::new(0.6, 0.45, 0.45), DVec3::X);
    let ratio = |f: &dyn Fn((DVec3, DVec3)) -> f64| f(behind) / f(beside);
    let exact = ratio(&|(x, n)| reference.leaving(x, n, Estimate::Exact)[0]);
    let depth_map = ratio(&|(x, n)| reference.leaving(x, n, Estimate::DepthMap)[0]);
    let scattered = Scattered::of(&cube, prepared(&cube).unwrap(), &lights, &s.objects).unwrap();
    let table = ratio(&|(x, n)| scattered.at(x, n)[0]);
    println!(
        "behind the cavity over beside it: reference {exact:.3}, table {table:.3}, depth map {depth_map:.3}"
    );
    assert!(
        exact > 1.5,
        "the cavity brightens the far face behind it: {exact}"
    );
    assert!(
        (table / exact - 1.0).abs() < 0.15,
        "the table: {table} against {exact}"
    );
    assert!(
        (depth_map / exact - 1.0).abs() > 0.3,
        "the depth map misses it: {depth_map} against {exact}"
    );
}

#[test]
fn the_table_is_symmetric_and_numbers_every_surface_voxel_once() {
    let object = sphere(2.0, 10);
    let v = Voxels::of(&object, 10).unwrap();
    let t = Table::of(&v);
    assert_eq!(t.tau.len(), v.surface.len() * (v.surface.len() + 1) / 2);
    assert_eq!(
        t.bytes(),
        energywave::objects::translucent::voxels::table_bytes(v.surface.len())
    );
    for (k, s) in v.surface.iter().enumerate() {
        assert_eq!(v.number[s.voxel], k as u32);
        assert_eq!(t.get(k, k), 0.0);
    }
    let numbered = v.number.iter().filter(|&&n| n != u32::MAX).count();
    assert_eq!(numbered, v.surface.len());
    // The surface's area, whatever the resolution: the sphere's 4 pi r^2 (its pieces flat, within 0.1 %).
    let area = 4.0 * std::f64::consts::PI * 0.49;
    assert!((v.area / area - 1.0).abs() < 1e-3, "{}", v.area);
    for (k, l) in [(0, 5), (3, 40), (17, 2), (v.surface.len() - 1, 0)] {
        assert_eq!(t.get(k, l), t.get(l, k));
        let exact = thickness(&v, v.surface[k].position, v.surface[l].position) as f32;
        assert!((t.get(k, l) - exact).abs() <= 1e-6 * exact.max(1.0));
    }
}

#[test]
fn a_source_inside_lights_the_surface_from_within() {
    // A point at the center of a sphere of extinction sigma: every surface point gets its term b / r, dimmed by
    // exp(-sigma r), and lets it out: S = b / r exp(-sigma r) / pi (no entry, no Fresnel on the way in).
    let mut s = scene("translucent_cavity");
    s.sources.tori.clear();
    s.sources.points.push(energywave::field::Point {
        position: DVec3::new(0.1, -0.2, 0.3),
        coefficient: 0.8,
        look: Default::default(),
    });
    let sigma = 1.2;
    let color = s.colors.palette().color_of(&Default::default());
    // Every surface voxel's light against the exact `b / r exp(-sigma r)` at its center, at every resolution: the
    // path from a source inside is measured through the medium itself, not the voxels (measured: 3.3e-8, the
    // color's f32).
    let mut worst = Vec::new();
    for resolution in [8, 16, 32] {
        let ball = sphere(sigma, resolution);
        s.objects = vec![ball.clone()];
        let lights = lights(&s);
        let p = prepared(&ball).unwrap();
        let medium = Medium::of(&ball).unwrap();
        let Irradiance { entering, inside } = irradiance(&medium, &p.voxels, &lights, &s.objects);
        assert!(entering.iter().all(|e| e[0] == 0.0));
        let off = (p.voxels.surface.iter().enumerate())
            .map(|(k, v)| {
                let r = (v.position - DVec3::new(0.1, -0.2, 0.3)).length();
                let want = 0.8 / r * (-sigma * r).exp() * color[0];
                (inside[k][0] / want - 1.0).abs()
            })
            .fold(0.0, f64::max);
        println!("{resolution}^3 voxels: worst relative error {off:e}");
        worst.push(off);
    }
    assert!(worst.iter().all(|&w| w < 1e-6), "{worst:?}");
    let ball = sphere(sigma, 16);
    s.objects = vec![ball.clone()];
    let lights = lights(&s);
    let reference = Reference::new(&ball, &s.objects, &lights, 0.05);
    let x = DVec3::new(0.1, -0.2, 0.3) + DVec3::Y * 0.7;
    let got = reference.leaving(x, DVec3::Y, Estimate::Exact)[0];
    let want = 0.8 / 0.7 * (-sigma * 0.7f64).exp() * color[0] / std::f64::consts::PI;
    assert!((got / want - 1.0).abs() < 1e-9, "{got} against {want}");
}

fn gpu() -> std::sync::MutexGuard<'static, energywave::gpu::HeadlessRenderer> {
    use std::sync::{Mutex, OnceLock};
    static GPU: OnceLock<Mutex<energywave::gpu::HeadlessRenderer>> = OnceLock::new();
    GPU.get_or_init(|| {
        Mutex::new(
            energywave::gpu::HeadlessRenderer::new().expect("a GPU adapter (lavapipe in CI)"),
        )
    })
    .lock()
    .unwrap_or_else(|e| e.into_inner())
}

/// Both presets, drawn by the GPU and by the f64 twin: the translucent objects' scattered light, the glow seen
/// through them, opaque, transparent and held out; and the first with a glare (which glares the glow undimmed by
/// the objects as it glares the glow, for the glow's edge).
#[test]
fn the_presets_compose_alike_on_the_gpu_and_the_cpu() {
    use energywave::frame::FrameSetup;
    use energywave::reference::{self, Backdrop};
    for (name, glare) in [
        ("translucent_cavity", false),
        ("crystal_beam", false),
        ("translucent_cavity", true),
    ] {
        let mut scene = scene(name);
        scene.billboard.resolution = 64;
        if glare {
            scene.glare = Some(energywave::scene::Glare::default());
        }
        let (w, h) = (96, 72);
        let bb = scene.place_billboard(w as f64 / h as f64);
        let setup = FrameSetup::new(&scene, bb);
        let tex = reference::render_brightness(&setup);
        // The glow through the objects differs from the glow they would clip: the see-through is in the field.
        let clipped = reference::render_brightness(&setup.front());
        let through = (tex.values.iter().zip(&clipped.values))
            .filter(|(a, b)| (*a - *b).abs() > 1e-3)
            .count();
        assert!(through > 50, "{name}: {through} texels see through");
        let mut g = gpu();
        for (backdrop, transparent, holdout) in [
            (Backdrop::Opaque, false, false),
            (Backdrop::Transparent, true, false),
            (Backdrop::Holdout, true, true),
        ] {
            let cpu = reference::compose_frame_over(&setup, &tex, (w, h), backdrop);
            g.set_holdout(holdout);
            let frame = g.render(&scene, w, h, transparent).unwrap();
            g.set_holdout(false);
            // Off by more than a few 8-bit steps only where a pixel's center lies on an object's edge (the GPU
            // rasterises what the CPU ray-casts, and a pixel astride an outline can go either way): each such
            // pixel within a pixel of an outline of some object, seen directly or through a translucent one (the
            // outlines cover 5 and 8 % of these frames; measured, no pixel differs at all, on Vulkan and GL).
            let edges = common::outline_pixels(&scene, w, h);
            for (k, (c, p)) in cpu.iter().zip(&frame.pixels).enumerate() {
                let differs = (0..4).any(|i| {
                    (c[i].clamp(0.0, 1.0) - (p[i] as f64).clamp(0.0, 1.0)).abs() > 4.0 / 255.0
                });
                assert!(
                    !differs || edges[k],
                    "{name} {backdrop:?}: pixel ({}, {}) differs away from every outline: CPU {c:?}, GPU {p:?}",
                    k % w as usize,
                    k / w as usize
                );
            }
            let lit = cpu.iter().filter(|p| p[0] + p[1] + p[2] > 0.05).count();
            assert!(
                lit * 4 > cpu.len(),
                "{name} {backdrop:?}: the picture is dark"
            );
        }
    }
}

fn invalid(text: &str) -> String {
    match Scene::parse(text, std::path::Path::new("bad.toml")) {
        Err(e) => e.to_string(),
        Ok(_) => panic!("accepted: {text}"),
    }
}

#[test]
fn translucent_materials_are_checked_with_located_errors_and_saved_back() {
    let head = "[[points]]\nposition = [0.0, 0.0, 0.0]\ncoefficient = 1.0\n";
    let cube = "[[objects]]\nshape = \"box\"\nsize = 1.0\n";
    for (body, field, says) in [
        (
            "[objects.translucent]\neta = 0.0\n",
            "objects[0].translucent.eta",
            "out of range",
        ),
        (
            "[objects.translucent]\neta = -1.3\n",
            "objects[0].translucent.eta",
            "out of range",
        ),
        (
            "[objects.translucent]\nextinction = -2.0\n",
            "objects[0].translucent.extinction",
            "out of range",
        ),
        (
            "[objects.translucent]\nresolution = 1\n",
            "objects[0].translucent.resolution",
            "out of range",
        ),
        (
            "[objects.translucent]\nresolution = 240\n",
            "objects[0].translucent.resolution",
            "MiB allowed",
        ),
        (
            "[objects.translucent.inner]\nshape = \"cone\"\nradius = 0.2\n",
            "objects[0].translucent.inner.shape",
            "not an inner shape",
        ),
        (
            "[objects.translucent.inner]\nshape = \"sphere\"\nradius = -0.2\n",
            "objects[0].translucent.inner.radius",
            "positive",
        ),
        (
            "[objects.translucent.noise]\nscale = 0.0\n",
            "objects[0].translucent.noise.scale",
            "positive",
        ),
        (
            "[objects.translucent]\ncolour = 1.0\n",
            "objects[0].translucent",
            "unknown field",
        ),
    ] {
        let e = invalid(&format!("{head}{cube}{body}"));
        assert!(e.contains(field) && e.contains(says), "{body}: {e}");
    }
    // The table too large says which resolution fits.
    let e = invalid(&format!(
        "{head}{cube}[objects.translucent]\nresolution = 240\n"
    ));
    assert!(e.contains("voxels a side or fewer fit"), "{e}");
    // A plane has no inside.
    let e = invalid(&format!(
        "{head}[[objects]]\nshape = \"plane\"\n[objects.translucent]\nextinction = 1.0\n"
    ));
    assert!(
        e.contains("objects[0].translucent") && e.contains("no inside"),
        "{e}"
    );
    // Saved and read back whole.
    let text = format!(
        "{head}{cube}[objects.translucent]\nextinction = 1.5\neta = 1.5\nresolution = 12\n\
         [objects.translucent.inner]\nshape = \"box\"\ncenter = [0.1, 0.0, 0.0]\nsize = [0.2, 0.3, 0.4]\nextinction = 0.5\n\
         [objects.translucent.noise]\nscale = 0.2\namount = 0.4\nseed = 3\n"
    );
    let scene = Scene::parse(&text, std::path::Path::new("ok.toml")).unwrap();
    let t = scene.objects[0].translucent.as_deref().unwrap();
    assert_eq!((t.extinction, t.eta, t.resolution), (1.5, 1.5, Some(12)));
    let again = Scene::parse(&scene.to_toml(), std::path::Path::new("ok.toml")).unwrap();
    assert_eq!(again.objects, scene.objects);
}

/// An open mesh (a tetrahedron missing a face) has no inside: the command line says so, exits 2 and writes
/// nothing.
#[test]
fn an_open_mesh_and_a_bad_material_fail_on_the_command_line() {
    let dir =
        std::env::temp_dir().join(format!("energywave-translucent-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // A glTF of three triangles of a tetrahedron: open.
    let p: [[f32; 3]; 4] = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    ];
    let indices: [u16; 9] = [0, 2, 1, 0, 1, 3, 0, 3, 2];
    let mut bin: Vec<u8> = p.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
    bin.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    std::fs::write(dir.join("open.bin"), &bin).unwrap();
    let gltf = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
"buffers":[{{"uri":"open.bin","byteLength":{}}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":18}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,0],"max":[1,1,1]}},
{{"bufferView":1,"componentType":5123,"count":9,"type":"SCALAR"}}]}}"#,
        bin.len()
    );
    std::fs::write(dir.join("open.gltf"), gltf).unwrap();
    let head = "[[points]]\nposition = [0.0, 0.0, 0.0]\ncoefficient = 1.0\n";
    for (body, field, says) in [
        (
            "[[objects]]\nshape = \"mesh\"\npath = \"open.gltf\"\n[objects.translucent]\nextinction = 1.0\n",
            "objects[0].translucent",
            "not closed",
        ),
        (
            "[[objects]]\nshape = \"sphere\"\nradius = 1.0\n[objects.translucent]\neta = 0.0\n",
            "objects[0].translucent.eta",
            "out of range",
        ),
    ] {
        let scene = dir.join("s.toml");
        std::fs::write(&scene, format!("{head}{body}")).unwrap();
        let err = common::render_refused(&scene, &dir.join("out.png"));
        assert!(
            err.contains(field) && err.contains(says) && err.contains("s.toml"),
            "{err}"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn extinction_and_eta_are_keyable() {
    use energywave::animation::{Parameter, TranslucentField};
    let p = Parameter::parse("objects[0].translucent.extinction").unwrap();
    assert_eq!(p, Parameter::Translucent(0, TranslucentField::Extinction));
    assert_eq!(p.to_string(), "objects[0].translucent.extinction");
    let mut text = std::fs::read_to_string("assets/scenes/translucent_cavity.toml").unwrap();
    text.push_str(
        "\n[animation]\nframes = 10\nframe_rate = 10\n[[animation.tracks]]\nparameter = \"objects[0].translucent.extinction\"\n\
         keys = [{ frame = 0, value = 0.5 }, { frame = 9, value = 3.0 }]\n",
    );
    let scene = Scene::parse(&text, std::path::Path::new("assets/scenes/keyed.toml")).unwrap();
    let at = |f: f64| {
        scene.at_frame(f).objects[0]
            .translucent
            .as_ref()
            .unwrap()
            .extinction
    };
    assert!(
        (at(0.0) - 0.5).abs() < 1e-12
            && (at(9.0) - 3.0).abs() < 1e-12
            && at(4.0) > 0.5
            && at(4.0) < 3.0
    );
    let bad = text.replace("value = 3.0", "value = -3.0");
    let e = invalid(&bad);
    assert!(e.contains("out of range"), "{e}");
}

/// The table filled on the GPU (f32, `gpu::tau_table`) against its CPU twin (f64, then f32), on the poster's
/// cube and the concave prism.
#[test]
fn the_gpu_fills_the_table_as_its_cpu_twin_does() {
    let g = gpu();
    for (name, object, resolution) in [
        ("cube with a cavity", cavity_cube(1.5, 12), 12),
        ("L-shaped prism", l_prism(1.0, 10), 10),
    ] {
        let v = Voxels::of(&object, resolution).unwrap();
        let cpu = Table::of(&v);
        let gpu_table = energywave::gpu::tau_table::tau_table(&g.ctx, &v).unwrap();
        assert_eq!(gpu_table.n, cpu.n);
        assert_eq!(gpu_table.tau.len(), cpu.tau.len());
        let largest = cpu.tau.iter().fold(0.0f32, |a, &b| a.max(b));
        let worst = (cpu.tau.iter().zip(&gpu_table.tau))
            .map(|(a, b)| (a - b).abs())
            .fold(0.0f32, f32::max);
        println!(
            "{name}: {} surface voxels, largest tau {largest}, worst |gpu - cpu| {worst:e}",
            cpu.n
        );
        assert!(largest > 1.0, "{name}: {largest}");
        assert!(worst <= 1e-4 * largest, "{name}: {worst} of {largest}");
    }
}

/// A clear object (extinction 0) spreads what enters evenly: every surface voxel lets out `P / (pi A)`, `P` the
/// power entering, `A` the surface's area. A source of negative coefficient darkens by exactly what the positive
/// one of the same size lightens (the light is linear in the sources).
#[test]
fn a_clear_object_glows_evenly_and_a_negative_source_darkens_by_as_much() {
    let object = cavity_cube(0.0, 10);
    let s = ring_scene(object.clone());
    let lights_of = |s: &Scene| lights(s);
    let p = prepared(&object).unwrap();
    let medium = Medium::of(&object).unwrap();
    let light = irradiance(&medium, &p.voxels, &lights_of(&s), &s.objects);
    let out = leaving(&p, &light);
    let power: f64 = (0..out.len())
        .map(|k| light.entering[k][0] * p.voxels.surface[k].area)
        .sum();
    let even = power / (std::f64::consts::PI * p.voxels.area);
    assert!(even > 0.0);
    for v in &out {
        assert!((v[0] / even - 1.0).abs() < 1e-9, "{} against {even}", v[0]);
    }
    // The ring's coefficient negated: every voxel's light negated.
    let mut dark = s.clone();
    dark.sources.tori[0].coefficient = -dark.sources.tori[0].coefficient;
    let light = irradiance(&medium, &p.voxels, &lights_of(&dark), &dark.objects);
    let negated = leaving(&p, &light);
    for (a, b) in out.iter().zip(&negated) {
        assert!(
            (a[0] + b[0]).abs() <= 1e-12 * a[0].abs().max(1.0),
            "{} and {}",
            a[0],
            b[0]
        );
    }
}

/// A point glowing at the center of a translucent sphere, seen through it: the glow the renderers blend
/// (`B_front + inside (B_exit - B_front) + behind (B - B_exit)`, the shares from `translucent::crossing`)
/// against the exact integral of the transmittance times the glow along each ray, `integral T psi zeta ds`, both
/// by fine Simpson on the same rays, so that the see-through model alone differs, `T` in closed form (the
/// sphere's chord and the Fresnel equations, none of the code under test), which `translucent::transmittance`
/// matches. Dimming the glow inside by the whole crossing (the two-field blend) is far off; the psi-weighted
/// share is close.
#[test]
fn a_source_inside_shows_through_as_the_exact_transmittance_weighted_glow() {
    use energywave::frame::FrameSetup;
    use energywave::integrate::zeta;
    use energywave::objects::translucent::{crossing, transmittance};
    let mut s = scene("translucent_cavity");
    s.sources.tori.clear();
    s.sources.points.push(energywave::field::Point {
        position: DVec3::ZERO,
        coefficient: 0.6,
        look: Default::default(),
    });
    s.objects = vec![Object {
        shape: Shape::Sphere {
            center: DVec3::ZERO,
            radius: 0.6,
        },
        color: [1.0; 3],
        translucent: material(1.5, 12),
    }];
    s.camera.eye = DVec3::new(0.0, 0.3, 4.0);
    s.camera.target = DVec3::ZERO;
    let setup = FrameSetup::placed(&s, 1.0);
    let (eye, nu) = (s.camera.eye, setup.reach.nu);
    let (alpha, beta) = (setup.integration.alpha, setup.integration.beta);
    let eps = s.integration.epsilon;
    let field = s.sources.field();
    let simpson = |f: &dyn Fn(f64) -> f64, a: f64, b: f64| simpson(f, (a, b), 20_000);
    // The share of light crossing the sphere (center 0, radius 0.6, extinction 1.5, index 1.4) from `from` to
    // `to` in closed form, as the model has it (straight through, no refraction): `exp(-sigma L)`, `L` the length of
    // the segment inside, times the Fresnel transmittance at every surface it crosses, at its angle there.
    let sphere_transmittance = |from: DVec3, to: DVec3| -> f64 {
        let (radius, sigma, eta) = (0.6, 1.5, 1.4);
        let d = to - from;
        let (a, b, c) = (d.dot(d), from.dot(d), from.dot(from) - radius * radius);
        let disc = b * b - a * c;
        if disc <= 0.0 {
            return 1.0;
        }
        let (t0, t1) = ((-b - disc.sqrt()) / a, (-b + disc.sqrt()) / a);
        let (enter, leave) = (t0.max(0.0), t1.min(1.0));
        if enter >= leave {
            return 1.0;
        }
        let crossed = [t0, t1].into_iter().filter(|t| (0.0..=1.0).contains(t));
        let fresnel: f64 = crossed
            .map(|t| fresnel_equations(eta, ((from + d * t) / radius).dot(d.normalize()).abs()))
            .product();
        fresnel * (-sigma * (leave - enter) * d.length()).exp()
    };
    let w = 64;
    let mut worst: [f64; 2] = [0.0; 2];
    for (i, j) in [(33, 32), (36, 30), (40, 35), (30, 38), (44, 32)] {
        let p = setup.billboard.texel_center(i, j, w);
        let end = eye + (p - eye) * nu;
        let at = |u: f64| p + (end - p) * u;
        let glow = |u: f64| field.psi(at(u), eps) * zeta(u, alpha, beta);
        let exact = simpson(&|u| sphere_transmittance(eye, at(u)) * glow(u), 0.0, 1.0);
        for u in [0.0, 0.1, 0.2, 0.3, 0.5, 1.0] {
            let (model, closed) = (
                transmittance(&s.objects, eye, at(u)),
                sphere_transmittance(eye, at(u)),
            );
            assert!(
                (model - closed).abs() < 1e-9,
                "the transmittance to {u}: {model} against {closed}"
            );
        }
        let psi = |x: DVec3| field.psi(x, eps);
        let x = crossing(&s.objects, eye, p, nu, &psi).expect("the ray crosses the sphere");
        let clip = |t: f64| ((t - 1.0) / (nu - 1.0)).clamp(0.0, 1.0);
        let first = s.objects[0].hit(eye, p - eye, 0.0, nu).unwrap();
        let (ca, cx) = (clip(first), clip(x.exit));
        let b = |c: f64| simpson(&glow, 0.0, c);
        let (ba, bx, bb) = (b(ca), b(cx), b(1.0));
        let model = ba + x.inside * (bx - ba) + x.behind * (bb - bx);
        let two_fields = ba + x.behind * (bb - ba);
        let errors = [
            (model / exact - 1.0).abs(),
            (two_fields / exact - 1.0).abs(),
        ];
        println!(
            "texel ({i}, {j}): exact {exact:.5}, blended {model:.5} ({:.2} %), dimmed by the whole crossing {two_fields:.5} ({:.1} %)",
            100.0 * errors[0],
            100.0 * errors[1]
        );
        worst = [worst[0].max(errors[0]), worst[1].max(errors[1])];
    }
    // The psi-weighted share is an estimate of the exact integral from 16 samples of the crossing (measured
    // 1.45 to 1.99 % off on these texels).
    assert!(worst[0] < 0.025, "{worst:?}");
    assert!(worst[1] > 4.0 * worst[0], "{worst:?}");
}

/// The Fresnel equations' unpolarised transmittance for relative index `eta` at the cosine `cos_i` of the angle
/// of incidence, written from the sine and tangent forms (`rs = -sin(i - t) / sin(i + t)`,
/// `rp = tan(i - t) / tan(i + t)`): the oracles' own, none of the code under test.
fn fresnel_equations(eta: f64, cos_i: f64) -> f64 {
    let i = cos_i.clamp(0.0, 1.0).acos();
    if i < 1e-9 {
        return 1.0 - ((eta - 1.0) / (eta + 1.0)).powi(2);
    }
    let sin_t = i.sin() / eta;
    if sin_t >= 1.0 {
        return 0.0;
    }
    let t = sin_t.asin();
    let rs = -(i - t).sin() / (i + t).sin();
    let rp = (i - t).tan() / (i + t).tan();
    1.0 - 0.5 * (rs * rs + rp * rp)
}

/// The model's light leaving a uniform sphere (radius `r`, extinction `sigma`, index `eta`) lit by a point of
/// coefficient `b` at distance `d` from its center, at the surface point `beta` radians from the source's side,
/// per unit of the source's color, worked out apart from the code under test: the chord between two surface
/// points `gamma` apart is `2 r sin(gamma / 2)` (so `tau` is closed form and needs no voxels or ray march), the
/// spread `Z = integral over the sphere of exp(-tau) = 2 pi (1 - exp(-2 r sigma) (1 + 2 r sigma)) / sigma^2` is
/// the same at every point, and the light entering at the point `alpha` from the source's side is
/// `E = F_t(eta, cos i) cos i b / dist`, `dist^2 = r^2 + d^2 - 2 r d cos alpha`, `cos i = (d cos alpha - r) / dist`
/// (no shadow: a sphere hides nothing of a point from its own lit side). Then
/// `S = (1 / pi) integral E exp(-tau) / Z dA`, in polar coordinates about the exit point (`gamma` by Simpson,
/// the angle around it by the trapezoid rule, exact for a periodic integrand), `n` steps each.
fn sphere_oracle(r: f64, sigma: f64, eta: f64, b: f64, d: f64, beta: f64, n: usize) -> f64 {
    use std::f64::consts::PI;
    let z = sphere_spread(r, sigma);
    let entering = |cos_alpha: f64| -> f64 {
        let dist = (r * r + d * d - 2.0 * r * d * cos_alpha).sqrt();
        let cos_i = (d * cos_alpha - r) / dist;
        match cos_i > 0.0 {
            true => fresnel_equations(eta, cos_i) * cos_i * b / dist,
            false => 0.0,
        }
    };
    let around = |gamma: f64| -> f64 {
        let m = 2 * n;
        (0..m)
            .map(|k| {
                let psi = 2.0 * PI * k as f64 / m as f64;
                entering(beta.cos() * gamma.cos() + beta.sin() * gamma.sin() * psi.cos())
            })
            .sum::<f64>()
            * 2.0
            * PI
            / m as f64
    };
    let chord = |gamma: f64| 2.0 * r * (gamma / 2.0).sin();
    let integral = simpson(
        &|gamma| around(gamma) * (-sigma * chord(gamma)).exp() * r * r * gamma.sin(),
        (0.0, PI),
        n,
    );
    integral / (z * PI)
}

/// A sphere's spread `Z = integral over its surface of exp(-tau)` from any point of it, in closed form: the
/// chord to a point `gamma` away is `c = 2 r sin(gamma / 2)` and `dA = 2 pi c dc`, so
/// `Z = 2 pi (1 - exp(-2 r sigma) (1 + 2 r sigma)) / sigma^2` (its area `4 pi r^2` where clear).
fn sphere_spread(r: f64, sigma: f64) -> f64 {
    use std::f64::consts::PI;
    match sigma > 0.0 {
        true => {
            2.0 * PI * (1.0 - (-2.0 * r * sigma).exp() * (1.0 + 2.0 * r * sigma)) / (sigma * sigma)
        }
        false => 4.0 * PI * r * r,
    }
}

/// Simpson's rule for `f` over `[a, b]` in `n` (even) steps.
fn simpson(f: &dyn Fn(f64) -> f64, (a, b): (f64, f64), n: usize) -> f64 {
    let h = (b - a) / n as f64;
    (0..=n)
        .map(|k| {
            let w = match k {
                0 => 1.0,
                k if k == n => 1.0,
                k if k % 2 == 1 => 4.0,
                _ => 2.0,
            };
            w * f(a + k as f64 * h)
        })
        .sum::<f64>()
        * h
        / 3.0
}

/// The translucent model against an oracle that shares none of its code (`sphere_oracle`): a sphere lit by a
/// point outside it, its light leaving at points from the lit pole round to the far one. The f64 model
/// (`translucent::reference`, its surface in small pieces and `tau` marched along each segment) agrees with it to
/// its pieces' size, and the voxels' table converges to it as the voxels shrink. The oracle's quadrature is
/// converged (n and 2 n agree) and its closed-form `Z` checked against the same quadrature with `E = 1`.
#[test]
fn a_sphere_lit_from_outside_scatters_as_its_closed_form() {
    let (r, b, d) = (0.7, 0.8, 2.0);
    let center = DVec3::new(0.1, -0.2, 0.3);
    let axis = DVec3::new(1.0, 0.3, -0.2).normalize();
    let across = axis.any_orthonormal_vector();
    let betas = [0.0f64, 30.0, 60.0, 90.0, 120.0, 150.0, 180.0].map(f64::to_radians);
    let point = |beta: f64| {
        let n = axis * beta.cos() + across * beta.sin();
        (center + n * r, n)
    };
    for sigma in [1.5, 5.0] {
        let oracle: Vec<f64> = betas
            .iter()
            .map(|&beta| sphere_oracle(r, sigma, 1.4, b, d, beta, 400))
            .collect();
        for (&beta, &o) in betas.iter().zip(&oracle) {
            let finer = sphere_oracle(r, sigma, 1.4, b, d, beta, 800);
            assert!(
                (finer / o - 1.0).abs() < 1e-6,
                "the oracle's quadrature at {beta}: {o} against {finer}"
            );
        }
        let mut s = scene("translucent_cavity");
        s.sources.tori.clear();
        assert!(s.sources.is_empty(), "the preset holds only the ring");
        s.sources.points.push(energywave::field::Point {
            position: center + axis * d,
            coefficient: b,
            look: Default::default(),
        });
        let color = s.colors.palette().color_of(&Default::default())[0];
        let ball = |resolution: u32| Object {
            shape: Shape::Sphere { center, radius: r },
            color: [1.0; 3],
            translucent: material(sigma, resolution),
        };
        s.objects = vec![ball(8)];
        let lights = lights(&s);
        let reference = Reference::new(&s.objects[0], &s.objects, &lights, 0.05);
        let mut worst = 0.0f64;
        for (&beta, &o) in betas.iter().zip(&oracle) {
            let (x, n) = point(beta);
            let got = reference.leaving(x, n, Estimate::Exact)[0] / color;
            println!(
                "sigma {sigma}, {:.0} degrees: oracle {o:.6}, f64 model {got:.6}",
                beta.to_degrees()
            );
            worst = worst.max((got / o - 1.0).abs());
        }
        assert!(
            worst < 5e-3,
            "sigma {sigma}: the f64 model {worst} off the oracle"
        );
        let mut errors = Vec::new();
        for resolution in [8, 12, 16, 24, 32] {
            let object = ball(resolution);
            let scattered = Scattered::of(
                &object,
                prepared(&object).unwrap(),
                &lights,
                std::slice::from_ref(&object),
            )
            .unwrap();
            let (mut num, mut den) = (0.0, 0.0);
            for (&beta, &o) in betas.iter().zip(&oracle) {
                let (x, n) = point(beta);
                num += (scattered.at(x, n)[0] / color - o).powi(2);
                den += o * o;
            }
            let e = (num / den).sqrt();
            println!("sigma {sigma}, {resolution}^3 voxels: relative RMS error {e:.4}");
            errors.push(e);
        }
        assert!(
            errors.windows(2).all(|w| w[1] < w[0]),
            "sigma {sigma}: {errors:?}"
        );
    }
    // The closed-form spread Z against the oracle's quadrature of exp(-tau) over the sphere.
    for sigma in [0.0, 1.5, 5.0] {
        let quadrature = simpson(
            &|gamma| {
                let chord = 2.0 * r * (gamma / 2.0).sin();
                2.0 * std::f64::consts::PI * (-sigma * chord).exp() * r * r * gamma.sin()
            },
            (0.0, std::f64::consts::PI),
            2000,
        );
        let z = sphere_spread(r, sigma);
        assert!(
            (quadrature / z - 1.0).abs() < 1e-9,
            "sigma {sigma}: Z {z} against {quadrature}"
        );
    }
}

/// The glow's edge (`colors.cutoff`) is the glow's own: a bright glow dimmed by a translucent object below the
/// cutoff still shows through it, dimmed, rather than being cut off there (the cube of translucent_cavity.toml
/// was crossed by dark wedges: the fade took B after the object had dimmed it, so every pixel whose dimmed glow
/// fell below the cutoff lost its glow altogether). A point glowing behind a translucent sphere, seen through it:
/// the texture's undimmed B is the glow without the object, and the frame shows the dimmed glow whole.
#[test]
fn a_glow_dimmed_by_a_translucent_object_below_the_cutoff_still_shows_through_it() {
    use energywave::frame::FrameSetup;
    use energywave::reference::{self, Backdrop, BrightnessTexture};
    let mut s = scene("translucent_cavity");
    s.sources.tori.clear();
    s.sources.points.push(energywave::field::Point {
        position: DVec3::new(0.0, 0.0, -1.2),
        coefficient: 1.0,
        look: Default::default(),
    });
    s.objects = vec![Object {
        shape: Shape::Sphere {
            center: DVec3::ZERO,
            radius: 0.6,
        },
        color: [0.2; 3],
        translucent: material(3.0, 12),
    }];
    s.camera.eye = DVec3::new(0.0, 0.0, 4.0);
    s.camera.target = DVec3::ZERO;
    s.colors.cutoff = 0.2;
    let setup = FrameSetup::placed(&s, 1.0);
    let glow = reference::render_brightness(&setup);
    let bare = Scene {
        objects: Vec::new(),
        ..s.clone()
    };
    let free = reference::render_brightness(&FrameSetup::placed(&bare, 1.0));
    let w = glow.resolution as usize;
    let center = (w / 2) * w + w / 2;
    let (dimmed, undimmed) = (glow.values[center], glow.undimmed[center]);
    // The undimmed glow is the glow without the object, texel by texel.
    let off = (glow.undimmed.iter().zip(&free.values))
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(
        off < 1e-9,
        "undimmed against the glow without the object: {off}"
    );
    // The case the test is for: bright behind the sphere, dimmed below the cutoff by it.
    assert!(
        undimmed > 2.0 * s.colors.cutoff && dimmed < s.colors.cutoff && dimmed > 0.02,
        "B {dimmed} dimmed, {undimmed} undimmed"
    );
    // The frame with the glow against the frame without it, at the center pixel: the glow's own share,
    // b (Ce - Cb), with b the dimmed B whole (the fade by the undimmed B is 1 there).
    let n = glow.values.len();
    let none = BrightnessTexture {
        resolution: glow.resolution,
        values: vec![0.0; n],
        tint: vec![[0.0; 3]; n],
        undimmed: vec![0.0; n],
    };
    let size = (33, 33);
    let with = reference::compose_frame_over(&setup, &glow, size, Backdrop::Opaque);
    let without = reference::compose_frame_over(&setup, &none, size, Backdrop::Opaque);
    let pixel = 16 * 33 + 16;
    let ce = s.colors.energy_color();
    let shown = (with[pixel][0] - without[pixel][0]) / (ce[0] - without[pixel][0]);
    assert!(
        (shown / dimmed - 1.0).abs() < 0.1,
        "the glow shown through the sphere {shown}, its dimmed B {dimmed}"
    );
}

/// A crossing's shares (`translucent::crossing`, which finds the surfaces and pieces along the ray once and reads
/// the transmittance to each of its 17 points off them) are the transmittance worked out afresh from the eye to
/// each point (`translucent::transmittance`, every object's surfaces and medium found again), weighted as the
/// crossing weighs them: for a box with a cavity turned about two axes, a sphere overlapping it, a concave mesh
/// and a noisy medium beside a uniform one (sampled, not read off), over rays that graze, cross one object or
/// several, and end at an opaque wall inside one.
#[test]
fn a_crossings_shares_are_the_transmittance_to_each_of_its_samples() {
    use energywave::objects::translucent::{CROSSING_SAMPLES, crossing, transmittance};
    let s = scene("translucent_cavity");
    let field = s.sources.field();
    let psi = |x: DVec3| field.psi(x, s.integration.epsilon);
    let mut turned = cavity_cube(1.5, 8);
    if let Shape::Box { rotation, .. } = &mut turned.shape {
        *rotation = DVec3::new(20.0, 35.0, 0.0);
    }
    let mut noisy = sphere(2.0, 8);
    noisy.translucent.as_mut().unwrap().noise = Some(energywave::objects::translucent::Noise {
        scale: 0.3,
        amount: 0.8,
        seed: 7,
    });
    let sets: [(&str, Vec<Object>); 4] = [
        ("turned cube, sphere", vec![turned.clone(), sphere(0.8, 8)]),
        ("cube", vec![cavity_cube(1.5, 8)]),
        ("L prism", vec![l_prism(1.2, 8)]),
        ("noisy sphere, cube", vec![noisy, cavity_cube(1.5, 8)]),
    ];
    let eye = DVec3::new(0.4, 0.9, 4.0);
    let mut compared = 0;
    for (name, objects) in &sets {
        for i in 0..24 {
            for j in 0..24 {
                // Off the objects' edges: a ray through a mesh's edge meets its triangles or not by rounding.
                let target = DVec3::new(-1.1 + 0.0973 * i as f64, -1.07 + 0.0991 * j as f64, 0.013);
                let s_point = eye + (target - eye) * 0.7;
                let d = s_point - eye;
                // Every third ray ends at an opaque wall through the middle of the objects.
                let end = if (i + j) % 3 == 0 { 1.0 / 0.7 } else { 3.0 };
                let Some(x) = crossing(objects, eye, s_point, end, &psi) else {
                    continue;
                };
                let at = |t: f64| eye + d * t;
                let (mut first, mut exit) = (f64::INFINITY, f64::NEG_INFINITY);
                for o in objects {
                    let mut a = 0.0;
                    while let Some(t) = o.hit(eye, d, a, end) {
                        (first, exit) = (first.min(t), exit.max(t));
                        a = t + 1e-12 * (1.0 + t);
                    }
                }
                let behind = transmittance(objects, eye, at(end));
                let (a, b) = (first.max(1.0), exit);
                let inside = if b > a {
                    let h = (b - a) / CROSSING_SAMPLES as f64;
                    let (mut sum, mut weight) = (0.0, 0.0);
                    for k in 0..CROSSING_SAMPLES {
                        let p = at(a + (k as f64 + 0.5) * h);
                        sum += psi(p).abs() * transmittance(objects, eye, p);
                        weight += psi(p).abs();
                    }
                    sum / weight
                } else {
                    behind
                };
                assert_eq!(x.exit, exit, "{name} ray ({i}, {j}): the last surface");
                // To rounding, but a ray that grazes a sphere (the cavity) meets it at roots of a discriminant
                // near 0, whose square root carries the rounding of the ray's scale (the whole ray here, the
                // segment to each point there) up to about 1e-8 of the chord: measured 2e-9 of a share.
                for (what, got, want) in
                    [("behind", x.behind, behind), ("inside", x.inside, inside)]
                {
                    assert!(
                        (got - want).abs() <= 1e-8 * want.max(1e-3),
                        "{name} ray ({i}, {j}): {what} {got} against {want}"
                    );
                }
                compared += 1;
            }
        }
    }
    assert!(compared > 600, "{compared} rays crossed the objects");
}

/// `translucent_cavity.toml` lit by a single point light of coefficient 1 at `light` instead of its ring.
fn lit_by_a_point(light: DVec3) -> Scene {
    let mut scene = scene("translucent_cavity");
    scene.sources.tori.clear();
    scene.sources.points.push(energywave::field::Point {
        position: light,
        coefficient: 1.0,
        look: Default::default(),
    });
    scene
}

/// The light a lone particle gets past `objects` over the light it gets with nothing between, every channel and
/// every entry of its quadratic form by the same factor (one source): that factor.
fn particle_light_share(scene: &Scene, objects: &[Object], at: DVec3) -> f64 {
    use energywave::particles::Particle;
    use energywave::particles::light::{light_particles, light_particles_among};
    let lights = lights(scene);
    let particle = [Particle {
        position: at,
        radius: 0.05,
        density: 1.0,
        color: [1.0; 3],
        emission: [0.0; 3],
    }];
    let (open, past) = (
        light_particles(&lights, &particle)[0],
        light_particles_among(&lights, objects, &particle)[0],
    );
    let share = past.iso[0] / open.iso[0];
    for c in 0..3 {
        assert!((past.iso[c] - share * open.iso[c]).abs() <= 1e-12 * open.iso[c].abs());
        for k in 0..6 {
            assert!((past.m[c][k] - share * open.m[c][k]).abs() <= 1e-12 * open.iso[c].abs());
        }
    }
    share
}

/// A particle is lit through a translucent object as the glow is seen through it, dimmed, not blocked, and an
/// opaque object stops the light: behind a glass sphere from a point source, the Fresnel transmittance at both
/// surfaces at their angles and `exp(-sigma L)` along the chord, all in closed form (the Fresnel equations
/// written apart); behind the same sphere made opaque, none; beside it, all; inside it, one surface and the
/// chord's part up to the particle; the light and the particle both inside a glass ball, `exp(-sigma d)`. A
/// ring's light partly hidden by an opaque wall is the share of its inverse-square weights seen, against 200,000
/// points of the ring tested against the wall by its planes: the shadow is soft, within the 32 stratified
/// points' 1/32.
#[test]
fn particles_are_lit_through_translucent_objects_dimmed_and_shadowed_by_opaque_ones() {
    let light = DVec3::new(-2.0, 0.1, 0.2);
    let mut scene = lit_by_a_point(light);
    let (center, radius, sigma, eta) = (DVec3::new(0.0, 0.0, 0.0), 0.6, 1.5, 1.4);
    let glass = common::glass_sphere(center, radius, sigma, eta);
    // The segment from the light to `x` against the sphere, in closed form.
    let closed = |x: DVec3| -> f64 {
        let d = x - light;
        let o = light - center;
        let (a, b, c) = (d.dot(d), o.dot(d), o.dot(o) - radius * radius);
        let disc = b * b - a * c;
        if disc <= 0.0 {
            return 1.0;
        }
        let roots = [(-b - disc.sqrt()) / a, (-b + disc.sqrt()) / a];
        let crossed: Vec<f64> = roots
            .into_iter()
            .filter(|t| (0.0..1.0).contains(t))
            .collect();
        if crossed.is_empty() {
            return 1.0;
        }
        let fresnel: f64 = (crossed.iter())
            .map(|&t| {
                let n = (light + d * t - center) / radius;
                fresnel_equations(eta, n.dot(d.normalize()).abs())
            })
            .product();
        let inside = roots[1].min(1.0) - roots[0].max(0.0);
        fresnel * (-sigma * inside * d.length()).exp()
    };
    let mut opaque = glass.clone();
    opaque.translucent = None;
    for (x, what) in [
        (DVec3::new(1.5, -0.1, 0.1), "behind"),
        (DVec3::new(1.2, 0.3, -0.2), "behind, off the axis"),
        (DVec3::new(0.2, 0.1, 0.0), "inside"),
        (DVec3::new(0.5, 1.4, 0.0), "beside"),
    ] {
        let want = closed(x);
        let through = particle_light_share(&scene, std::slice::from_ref(&glass), x);
        // To 1e-8: a shadow ray leaves out 1e-9 of the scene's scale at either end (its ends' own surfaces).
        assert!(
            (through - want).abs() <= 1e-8,
            "{what}: through the glass {through} against {want}"
        );
        let past = particle_light_share(&scene, std::slice::from_ref(&opaque), x);
        let want = if want == 1.0 { 1.0 } else { 0.0 };
        assert_eq!(past, want, "{what}: past the opaque sphere");
        if what == "behind" {
            assert!(through > 0.05 && through < 0.5, "{through}");
        }
    }
    // The light and the particle both inside a glass ball: no surface between them, the medium all the way.
    let ball = common::glass_sphere(light, 1.0, sigma, eta);
    let x = light + DVec3::new(0.5, 0.3, -0.2);
    let want = (-sigma * (x - light).length()).exp();
    let within = particle_light_share(&scene, std::slice::from_ref(&ball), x);
    assert!(
        (within - want).abs() <= 1e-8,
        "both inside: {within} against {want}"
    );
    // A ring in the x = -2 plane, a wall between it and the particle hiding its lower part.
    scene.sources.points.clear();
    scene.sources.tori.push(energywave::field::Torus {
        center: DVec3::new(-2.0, 0.0, 0.0),
        axis: DVec3::X,
        major_radius: 0.8,
        coefficient: 1.0,
        look: Default::default(),
    });
    let (lo, hi) = (DVec3::new(-1.2, -2.0, -2.0), DVec3::new(-1.0, 0.1, 2.0));
    let wall = Object {
        shape: Shape::Box {
            center: (lo + hi) * 0.5,
            size: hi - lo,
            rotation: DVec3::ZERO,
        },
        color: [1.0; 3],
        translucent: None,
    };
    let x = DVec3::new(0.5, 0.05, 0.1);
    let hidden = |p: DVec3| -> bool {
        // The segment p -> x against the box by its slabs.
        let d = x - p;
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        for a in 0..3 {
            let (u, v) = ((lo[a] - p[a]) / d[a], (hi[a] - p[a]) / d[a]);
            t0 = t0.max(u.min(v));
            t1 = t1.min(u.max(v));
        }
        t0 < t1
    };
    let n = 200_000;
    let (mut seen, mut all) = (0.0, 0.0);
    for k in 0..n {
        let a = (k as f64 + 0.5) * std::f64::consts::TAU / n as f64;
        let p = DVec3::new(-2.0, 0.8 * a.cos(), 0.8 * a.sin());
        let w = 1.0 / (x - p).length_squared();
        all += w;
        if !hidden(p) {
            seen += w;
        }
    }
    let want = seen / all;
    let got = particle_light_share(&scene, std::slice::from_ref(&wall), x);
    println!("the ring past the wall: {got:.4} against {want:.4}");
    assert!(
        want > 0.2 && want < 0.8,
        "the wall hides part of the ring: {want}"
    );
    assert!((got - want).abs() <= 1.0 / 32.0, "{got} against {want}");
}

/// An object in a translucent object's shadow gets the light the translucent one lets through, not none: a floor
/// point under a glass sphere from a point light gets the Fresnel transmittance at both surfaces times
/// `exp(-sigma L)` (closed form, the Fresnel equations written apart) of the light it gets with nothing between,
/// none under the sphere made opaque; the soft shadow of a ring through a glass slab lies between the ring's
/// light through the slab and all of it, and is the ring's light through the slab where the slab hides all of
/// the ring.
#[test]
fn objects_in_a_translucent_objects_shadow_get_the_light_it_lets_through() {
    let light = DVec3::new(0.3, 2.5, -0.2);
    let mut scene = lit_by_a_point(light);
    let (center, radius, sigma, eta) = (DVec3::new(0.1, 1.0, 0.0), 0.5, 1.2, 1.45);
    let glass = common::glass_sphere(center, radius, sigma, eta);
    let mut opaque = glass.clone();
    opaque.translucent = None;
    let lights = lights(&scene);
    let up = DVec3::Y;
    for x in [DVec3::new(0.0, 0.0, 0.1), DVec3::new(-0.25, 0.0, -0.3)] {
        // The segment from the light to x against the sphere.
        let d = x - light;
        let o = light - center;
        let (a, b, c) = (d.dot(d), o.dot(d), o.dot(o) - radius * radius);
        let disc = b * b - a * c;
        assert!(disc > 0.0, "{x} lies in the sphere's shadow");
        let (t0, t1) = ((-b - disc.sqrt()) / a, (-b + disc.sqrt()) / a);
        let fresnel: f64 = [t0, t1]
            .iter()
            .map(|&t| {
                fresnel_equations(
                    eta,
                    ((light + d * t - center) / radius).dot(d.normalize()).abs(),
                )
            })
            .product();
        let want = fresnel * (-sigma * (t1 - t0) * d.length()).exp();
        let got = lights.visibility(std::slice::from_ref(&glass), x, up, 0, light);
        assert!((got - want).abs() <= 1e-8, "{x}: {got} against {want}");
        let open = lights.irradiance(&[], x, up);
        let past = lights.irradiance(std::slice::from_ref(&glass), x, up);
        let dark = lights.irradiance(std::slice::from_ref(&opaque), x, up);
        let ambient = energywave::objects::lighting::AMBIENT;
        for ch in 0..3 {
            assert!(((past[ch] - ambient) - want * (open[ch] - ambient)).abs() <= 1e-8);
            assert!((dark[ch] - ambient).abs() <= 1e-12);
        }
    }
    // A ring overhead and a glass slab between it and a floor point: a slab wider than the ring's shadow hides
    // all of it behind the same glass; a narrower one leaves part of the ring in sight.
    scene.sources.points.clear();
    scene.sources.tori.push(energywave::field::Torus {
        center: DVec3::new(0.0, 2.0, 0.0),
        axis: DVec3::Y,
        major_radius: 0.8,
        coefficient: 1.0,
        look: Default::default(),
    });
    let lights = energywave::objects::lighting::Lights::new(
        &scene.sources,
        scene.colors.palette(),
        scene.integration.epsilon,
    );
    let slab = |width: f64| Object {
        shape: Shape::Box {
            center: DVec3::new(0.0, 1.0, 0.0),
            size: DVec3::new(width, 0.1, width),
            rotation: DVec3::ZERO,
        },
        color: [1.0; 3],
        translucent: Some(Box::new(Translucent {
            extinction: 2.0,
            eta: 1.3,
            inner: None,
            noise: None,
            resolution: Some(8),
        })),
    };
    let x = DVec3::new(0.05, 0.0, 0.0);
    let nearest = DVec3::new(0.8, 2.0, 0.0);
    let wide = lights.visibility(&[slab(4.0)], x, up, 0, nearest);
    // Through the slab's faces at the nearest point's angle, the light its path crosses: the oracle's.
    let d = nearest - x;
    let cos = d.normalize().y;
    let path = 0.1 / cos;
    let through_nearest = fresnel_equations(1.3, cos).powi(2) * (-2.0 * path).exp();
    // Every point of the ring is as far from x and crosses the slab at nearly the same angle: the share is the
    // light through the slab at about that angle (x lies 0.05 off the axis).
    assert!(
        (wide - through_nearest).abs() < 0.01,
        "the slab hides the whole ring: {wide} against {through_nearest}"
    );
    let narrow = lights.visibility(&[slab(0.7)], x, up, 0, nearest);
    assert!(
        narrow > wide + 0.05 && narrow < 1.0,
        "part of the ring in sight: {narrow} (all of it behind the glass: {wide})"
    );
}
