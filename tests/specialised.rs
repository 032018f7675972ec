//! The field pass specialised to the scene's structure (pipeline-overridable constants: source counts, the
//! Gauss-Kronrod order, jitter) gives the texture of the generic pass, every layer of it (B, the tint's three),
//! on every shipped scene (a color per source, a color series, objects' clips) with every integrator and both
//! decays; and a structure compiled in the background is used once ready, never waited for.

use energywave::frame::FrameSetup;
use energywave::gpu::{
    FieldInputs, FieldRenderer, GpuContext, Specialise, Structure, read_texture_layer,
};
use energywave::integrate::{Decay, Integrator};
use energywave::scene::Scene;

mod common;
use common::shipped;

/// The field of `scene` through `field` (integrated again), layer 0 (B) read back.
fn field_of(ctx: &GpuContext, field: &mut FieldRenderer, scene: &Scene) -> Vec<f32> {
    let (device, queue) = (&ctx.device, &ctx.queue);
    field.invalidate();
    field
        .prepare(
            device,
            queue,
            &FieldInputs::of(&FrameSetup::placed(scene, 1.0)),
        )
        .unwrap();
    let mut encoder = device.create_command_encoder(&Default::default());
    field.encode(&mut encoder);
    ctx.checked(|| queue.submit([encoder.finish()])).unwrap();
    bytemuck::cast_slice(&ctx.read_texture(field.texture().unwrap(), 4).unwrap()).to_vec()
}

/// Every layer the field pass writes for `scene` (B, and the tint's three where the scene has colors), integrated
/// again through `field`, one after the other.
fn layers_of(ctx: &GpuContext, field: &mut FieldRenderer, scene: &Scene) -> Vec<f32> {
    field_of(ctx, field, scene);
    let texture = field.texture().unwrap();
    (0..energywave::gpu::layers_of(scene))
        .flat_map(|layer| {
            let bytes = read_texture_layer(&ctx.device, &ctx.queue, texture, 4, layer).unwrap();
            bytemuck::cast_slice::<u8, f32>(&bytes).to_vec()
        })
        .collect()
}

#[test]
fn the_specialised_field_pass_gives_the_generic_texture() {
    let ctx = GpuContext::new().expect("a GPU adapter (lavapipe in CI)");
    let mut generic = FieldRenderer::new(&ctx.device);
    generic.set_specialise(Specialise::Off);
    let mut specialised = FieldRenderer::new(&ctx.device);
    specialised.set_specialise(Specialise::Blocking);
    let mut worst = 0.0f64;
    let mut identical = 0;
    let (mut cases, mut tinted, mut clipped) = (0, 0, 0);
    for (name, base) in shipped() {
        for (integrator, jitter, decay) in [
            (Integrator::Adaptive, None, Decay::Distance),
            (Integrator::Simpson, None, Decay::Distance),
            (Integrator::Simpson, Some(7), Decay::Distance),
            (Integrator::Adaptive, None, Decay::Rms),
            (Integrator::Simpson, None, Decay::Rms),
        ] {
            let mut scene = base.clone();
            scene.billboard.resolution = 24;
            scene.animation = None;
            scene.integration.integrator = integrator;
            scene.integration.jitter = jitter;
            scene.integration.divisions = 64;
            scene.integration.decay = decay;
            let a = layers_of(&ctx, &mut generic, &scene);
            let b = layers_of(&ctx, &mut specialised, &scene);
            let layers = energywave::gpu::layers_of(&scene);
            assert_eq!(a.len(), (24 * 24 * layers) as usize);
            tinted += usize::from(layers > 1);
            clipped += usize::from(!scene.objects.is_empty());
            let structure = Structure::of_frame(&FrameSetup::placed(&scene, 1.0));
            assert!(
                specialised.specialised_ready(&structure),
                "{name}: compiled"
            );
            assert!(!generic.specialised_ready(&structure));
            for (k, (&x, &y)) in a.iter().zip(&b).enumerate() {
                let relative = (x as f64 - y as f64).abs() / (x.abs() as f64).max(0.01);
                assert!(
                    relative <= 1e-5,
                    "{name}, {integrator:?} jitter {jitter:?} {decay:?}, layer {}, texel {}: generic {x}, \
                     specialised {y}",
                    k / (24 * 24),
                    k % (24 * 24)
                );
                worst = worst.max(relative);
            }
            identical += usize::from(a == b);
            cases += 1;
        }
    }
    // The shipped scenes hold a color per source and a color series (rings_and_beam) and objects (floor).
    assert!(
        tinted >= 5 && clipped >= 5,
        "{tinted} tinted, {clipped} clipped cases"
    );
    eprintln!(
        "specialised against generic: worst relative difference {worst:.1e}; {identical} of {cases} textures identical"
    );
}

#[test]
fn a_structure_compiles_in_the_background_and_is_used_once_ready() {
    let ctx = GpuContext::new().expect("a GPU adapter (lavapipe in CI)");
    let mut field = FieldRenderer::new(&ctx.device);
    field.set_specialise(Specialise::Background);
    let mut scene = Scene::default_scene();
    scene.billboard.resolution = 16;
    let structure = Structure::of_frame(&FrameSetup::placed(&scene, 1.0));
    let first = field_of(&ctx, &mut field, &scene);
    if ctx.adapter.get_info().backend == wgpu::Backend::Gl {
        // GL compiles on no thread of its own (it would hold the one GL context every frame waits on): the
        // generic pipelines keep drawing, and nothing is compiled.
        for _ in 0..3 {
            assert_eq!(field_of(&ctx, &mut field, &scene), first);
        }
        assert!(!field.compiling() && !field.specialised_ready(&structure));
        assert!(field.compile_times().is_empty());
        return;
    }
    // The first dispatch ran on the generic pipelines and started the compile.
    let start = std::time::Instant::now();
    while !field.specialised_ready(&structure) {
        assert!(start.elapsed().as_secs() < 120, "the compile finishes");
        std::thread::sleep(std::time::Duration::from_millis(20));
        field_of(&ctx, &mut field, &scene);
    }
    assert!(!field.compiling());
    assert_eq!(field.compile_times().len(), 1);
    let (compiled, ms) = field.compile_times()[0];
    assert_eq!(compiled, structure);
    eprintln!("compiled {structure:?} in {ms:.0} ms");
    let again = field_of(&ctx, &mut field, &scene);
    for (&x, &y) in first.iter().zip(&again) {
        assert!((x as f64 - y as f64).abs() <= 1e-5 * (x.abs() as f64).max(0.01));
    }
    // A value edit keeps the structure: nothing compiles.
    scene.sources.tori[0].coefficient *= 1.5;
    field_of(&ctx, &mut field, &scene);
    assert!(!field.compiling() && field.compile_times().len() == 1);
}

/// An editing session passes through many structures; only the most recently drawn keep their pipelines
/// (each holds the driver's machine code), so memory stays bounded however many were drawn.
#[test]
fn only_the_latest_structures_keep_their_pipelines() {
    let ctx = GpuContext::new().expect("a GPU adapter (lavapipe in CI)");
    let mut field = FieldRenderer::new(&ctx.device);
    field.set_specialise(Specialise::Blocking);
    let mut scene = Scene::default_scene();
    scene.billboard.resolution = 8;
    scene.integration.integrator = Integrator::Simpson;
    scene.integration.divisions = 8;
    let mut structures = Vec::new();
    for k in 0..9 {
        scene.sources.points.push(energywave::field::Point {
            position: glam::DVec3::new(k as f64 * 0.1, 0.0, 0.0),
            coefficient: 0.5,
            look: Default::default(),
        });
        field_of(&ctx, &mut field, &scene);
        structures.push(Structure::of_frame(&FrameSetup::placed(&scene, 1.0)));
    }
    let kept = structures
        .iter()
        .filter(|s| field.specialised_ready(s))
        .count();
    assert!((1..=4).contains(&kept), "{kept} structures kept");
    assert!(field.specialised_ready(structures.last().unwrap()));
    assert!(
        !field.specialised_ready(&structures[0]),
        "the oldest was dropped"
    );
    assert_eq!(field.compile_times().len(), 9);
}

/// The bench's baseline, a plainly written kernel specialised to the scene (`bench::PlainKernels`), integrates
/// what the papers' Simpson's rule gives in f64 (the twin) on the papers' scenes: our pass is timed against a
/// kernel that computes the same picture, not a cheaper one. The Bezier scene at 256 x 256, n = 256, in the band
/// of rows where rays graze the chain (Cardano's root unpolished left B 0.063 off there); the torus whole at
/// 40 x 40, and the chain weighed by a uniform W series; its values constants of its text and read from a buffer.
/// Scenes it is not written for are refused.
#[test]
fn the_plain_kernel_the_bench_times_ours_against_gives_the_twins_simpson() {
    use energywave::bench::{Baked, PlainKernels, plain_unsupported};
    let ctx = GpuContext::new().expect("a GPU adapter (lavapipe in CI)");
    let mut plain = PlainKernels::new();
    for (name, w, n, rows) in [
        ("bezier_b5.0.toml", 256, 256, 118..140),
        ("torus_r0.9_t5.1.toml", 40, 64, 0..40),
        ("mixed.toml", 40, 64, 0..40),
    ] {
        let mut scene = common::shipped_scene(name);
        scene.integration.integrator = Integrator::Simpson;
        scene.billboard.resolution = w;
        scene.integration.divisions = n;
        if let Some(why) = plain_unsupported(&scene) {
            // mixed.toml has a chain with a W series: the plain kernel is not written for it.
            assert_eq!(name, "mixed.toml", "{why}");
            assert!(plain.brightness(&ctx, &scene, Baked::All).is_err());
            continue;
        }
        let all = plain.brightness(&ctx, &scene, Baked::All).unwrap();
        let buffered = plain.brightness(&ctx, &scene, Baked::Structure).unwrap();
        let setup = FrameSetup::placed(&scene, 1.0);
        let (mut largest, mut off) = (0.0f64, 0.0f64);
        for j in rows {
            for i in 0..w {
                let twin = energywave::reference::texel_brightness(&setup, i, j);
                largest = largest.max(twin.abs());
                for gpu in [&all, &buffered] {
                    off = off.max((gpu[(j * w + i) as usize] as f64 - twin).abs());
                }
            }
        }
        assert!(largest > 1.0, "{name}: a lit picture ({largest})");
        assert!(
            off <= 2e-5 * largest,
            "{name}: {off} off, B up to {largest}"
        );
    }
    // A W series of equal weights weighs the chain by that weight everywhere; the plain kernel takes it.
    let mut scene = common::shipped_scene("bezier_b5.0.toml");
    scene.integration.integrator = Integrator::Simpson;
    scene.billboard.resolution = 24;
    scene.integration.divisions = 64;
    scene.sources.curves[0].weights = vec![2.5; 4];
    assert_eq!(plain_unsupported(&scene), None);
    let gpu = plain.brightness(&ctx, &scene, Baked::Structure).unwrap();
    let twin = energywave::reference::render_brightness(&FrameSetup::placed(&scene, 1.0)).values;
    let largest = twin.iter().fold(0.0f64, |m, b| m.max(b.abs()));
    let off = (gpu.iter().zip(&twin)).fold(0.0f64, |m, (a, b)| m.max((*a as f64 - b).abs()));
    assert!(
        largest > 1.0 && off <= 2e-5 * largest,
        "{off} off, B up to {largest}"
    );
}
