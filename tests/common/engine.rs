//! What the engine shader's tests share (`tests/engine.rs`: GLSL 4.50 and HLSL as SPIR-V on Vulkan;
//! `tests/engine_es.rs`: GLSL ES 3.00 on GLES): the scenes that reach every part of the shader, the frame they are
//! drawn in with the exported uniforms as they are, and the check of each drawn pixel against the f64 twin.

use energywave::frame::FrameSetup;
use energywave::integrate::{Decay, Integrator};
use energywave::scene::Scene;

/// The frame the stages are drawn in, and the aspect the uniforms are exported for (`EffectShader::of`).
pub const FRAME: (u32, u32) = (80, 60);

/// What a pixel the quad does not cover holds: the target is cleared to it.
pub const CLEAR: [f32; 4] = [-1e9; 4];

/// Scenes that reach every part of the shader, Simpson's rule at the papers' n: points, lines, tori, curves with
/// W and color series, the rms decay, the brightest-point W form, and a glow with an edge seen from afar, whose
/// billboard's edges lie inside the frame.
pub fn scenes() -> Vec<(String, Scene)> {
    let mut out = Vec::new();
    for name in [
        "default",
        "mixed",
        "pulse_travelling",
        "rings_and_beam",
        "bezier_b5.0",
    ] {
        let mut scene = super::shipped_scene(&format!("{name}.toml"));
        scene.integration.integrator = Integrator::Simpson;
        out.push((name.to_owned(), scene));
    }
    let (_, mixed) = out[1].clone();
    let mut rms = mixed;
    rms.integration.decay = Decay::Rms;
    out.push(("mixed, rms".into(), rms));
    let (_, pulse) = out[2].clone();
    let mut bright = pulse.at_frame(30.0);
    (bright.sources.curves.iter_mut())
        .for_each(|c| c.w_form = energywave::field::WForm::Continuous);
    out.push(("pulse_travelling, continuous W".into(), bright));
    // The billboard is sized to the effect where the glow has an edge (cutoff above 0); from eight times as far,
    // its edges lie inside the frame.
    let (_, default) = out[0].clone();
    let mut edged = default;
    edged.colors.cutoff = 0.05;
    let c = &mut edged.camera;
    c.eye = c.target + (c.eye - c.target) * 8.0;
    out.push(("default from afar, cutoff 0.05".into(), edged));
    out
}

/// The engine's `brightness` (B and the tint) and `glow` (premultiplied color, alpha) stages drawn over `FRAME`
/// with the scene's exported uniforms (its camera), rows from the top, against the f64 twin's Simpson along each
/// pixel's own ray: the camera's ray through the pixel's center, met with the billboard's plane, continued to the
/// ray's reach. A pixel whose center lies more than a pixel inside the billboard is drawn and within the bound
/// the twins hold each other to on Simpson (f32's rounding, as in tests/robustness.rs); one more than a pixel
/// outside is not drawn (the raster's edge rule decides between). So a wrong camera number (a `view_proj` off by
/// a pixel, a billboard placed for another aspect) fails as a wrong field does. The tint (the sources' own colors) is
/// held to the twin's alike. Returns what it compared, for the log: pixels compared, pixels left clear, the worst
/// relative error of B and the tint, the largest B.
pub fn check_against_twin(
    name: &str,
    scene: &Scene,
    brightness: &[[f32; 4]],
    glow: &[[f32; 4]],
) -> (usize, usize, f64, f64) {
    let (width, height) = FRAME;
    let aspect = width as f64 / height as f64;
    let setup = FrameSetup::placed(scene, aspect);
    let (bb, eye, nu) = (setup.billboard, setup.eye(), setup.reach.nu);
    let pixel_side = 2.0 * (bb.center - eye).length() * scene.camera.tan_half_fov() / height as f64;
    let (mut compared, mut worst, mut top, mut worst_tint) = (0, 0.0f64, 0.0f64, 0.0f64);
    for y in 0..height {
        for x in 0..width {
            let k = (y * width + x) as usize;
            let dir = scene
                .camera
                .pixel_ray(x as f64 + 0.5, y as f64 + 0.5, width, height);
            let s = eye + dir * ((bb.center - eye).dot(bb.normal) / dir.dot(bb.normal));
            let (u, v) = ((s - bb.center).dot(bb.right), (s - bb.center).dot(bb.up));
            let inside = (bb.size / 2.0 - u.abs().max(v.abs())) / pixel_side;
            let drawn = brightness[k][0] != CLEAR[0];
            if inside < -1.0 {
                assert!(
                    !drawn,
                    "{name}: pixel ({x}, {y}), {:.1} pixels outside the billboard, drawn",
                    -inside
                );
            }
            if inside <= 1.0 {
                continue;
            }
            assert!(
                drawn,
                "{name}: pixel ({x}, {y}), {inside:.1} pixels inside the billboard, not drawn"
            );
            let e = energywave::geometry::ray_end(s, eye, nu);
            let want = energywave::reference::field_pass::brightness(
                &scene.sources,
                &setup.integration,
                s,
                e,
                0.5,
            );
            let got = brightness[k][0] as f64;
            assert!(
                (got - want).abs() <= 1.5e-4 * want.abs().max(0.01),
                "{name}: pixel ({x}, {y}): the engine's B {got}, the twin's {want}"
            );
            // The tint, the sources' own colors: sum B_i (Ce_i - Ce), its channels as large as B times a color.
            let tint =
                energywave::reference::field_pass::tint_of(&setup, &setup.integration, (s, e), 0.5);
            for c in 0..3 {
                let (got, want_c) = (brightness[k][1 + c] as f64, tint[c]);
                assert!(
                    (got - want_c).abs() <= 1.5e-4 * want.abs().max(want_c.abs()).max(0.01),
                    "{name}: pixel ({x}, {y}): the engine's tint {got} in channel {c}, the twin's {want_c}"
                );
                worst_tint =
                    worst_tint.max((got - want_c).abs() / want.abs().max(want_c.abs()).max(0.01));
            }
            worst = worst.max((got - want).abs() / want.abs().max(0.01));
            top = top.max(want.abs());
            compared += 1;
            // The glow stage: alpha min(B, 1) faded at the glow's edge, its color G = B Ce + tint premultiplied.
            let fade = energywave::scene::edge_fade(got, scene.colors.cutoff);
            let alpha = (got * fade).clamp(0.0, 1.0);
            assert!(
                (glow[k][3] as f64 - alpha).abs() < 1e-4,
                "{name}: pixel ({x}, {y}): alpha {} for B {got}",
                glow[k][3]
            );
            for (c, energy) in scene.colors.energy_color().into_iter().enumerate() {
                let color = (fade * (got * energy + brightness[k][1 + c] as f64)).max(0.0);
                assert!(
                    (glow[k][c] as f64 - color).abs() < 1e-4 * color.abs().max(1.0),
                    "{name}: pixel ({x}, {y}): premultiplied {:?}, channel {c} should be {color}",
                    glow[k]
                );
            }
        }
    }
    let outside = brightness.iter().filter(|p| p[0] == CLEAR[0]).count();
    assert!(
        compared > (width * height / 8) as usize,
        "{name}: {compared} pixels on the billboard"
    );
    assert!(top > 0.05, "{name}: a glow to compare ({top})");
    // Where the placement says the billboard's edges lie inside the frame (its edge band), pixels lie outside it.
    assert_eq!(
        outside > 0,
        bb.edge > 0.0,
        "{name}: {outside} pixels outside the billboard, its edge band {}",
        bb.edge
    );
    (compared, outside, worst.max(worst_tint), top)
}
