//! The billboard pass's f64 twin (`shaders/billboard.wgsl`): the final blend and the composed frame (METHOD.md
//! section 4, thesis 4.8).
//!
//! Colors are display values in [0, 1] (as an artist picks them), blended as they are, the way the papers
//! blend: `color = clamp((1 - B) Cb + B Ce)`. B above 1 blows the glow out toward white by design.

use glam::DVec3;
use rayon::prelude::*;

use super::field_pass::BrightnessTexture;
use super::objects::ObjectImage;
use crate::frame::FrameSetup;
use crate::geometry::Billboard;
use crate::objects::clip::clip_fractions;
use crate::scene::Blend;

/// `clamp((1 - B) Cb + B Ce, 0, 1)` per channel.
pub fn blend(b: f64, energy: [f64; 3], background: [f64; 3]) -> [f64; 3] {
    blend_glow(b, energy.map(|c| b * c), background)
}

/// `clamp((1 - B) Cb + G, 0, 1)` per channel, G the glow's colored sum `sum B_i Ce_i` (`B Ce` with one color):
/// the papers' blend with a color per source.
pub fn blend_glow(b: f64, glow: [f64; 3], background: [f64; 3]) -> [f64; 3] {
    papers_unclamped(b, glow, background).map(|c| c.clamp(0.0, 1.0))
}

/// `(1 - B) Cb + G` per channel: the papers' blend before its clamp.
fn papers_unclamped(b: f64, glow: [f64; 3], background: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|c| (1.0 - b) * background[c] + glow[c])
}

/// `max(G, 0) + (1 - clamp(B, 0, 1)) Cb` per channel: "over" before its clamp.
fn over_unclamped(b: f64, glow: [f64; 3], background: [f64; 3]) -> [f64; 3] {
    let alpha = b.clamp(0.0, 1.0);
    std::array::from_fn(|c| glow[c].max(0.0) + (1.0 - alpha) * background[c])
}

/// `clamp(B Ce + (1 - min(B, 1)) Cb)` per channel, B below 0 taken as 0 (`Blend::Over`): the transparent export
/// composited over Cb, clamped, for every B.
pub fn blend_over(b: f64, energy: [f64; 3], background: [f64; 3]) -> [f64; 3] {
    blend_over_glow(b, energy.map(|c| b * c), background)
}

/// `clamp(max(G, 0) + (1 - clamp(B, 0, 1)) Cb)` per channel: `blend_over` with the colored sum G.
pub fn blend_over_glow(b: f64, glow: [f64; 3], background: [f64; 3]) -> [f64; 3] {
    over_unclamped(b, glow, background).map(|c| c.clamp(0.0, 1.0))
}

/// The transparent export of one billboard pixel: associated (premultiplied) color `B Ce`, unclamped, and
/// alpha = min(B, 1). Composited "over" any background Cb (`color + (1 - alpha) Cb`) it gives `(1 - B) Cb + B Ce`
/// wherever B <= 1, and over black `B Ce` everywhere, which the display clamps as the opaque blend does. B > 1
/// cannot be an alpha: there the glow covers the background (the opaque blend's `(1 - B) Cb` would subtract
/// it). B < 0 (negative coefficients) is transparent.
pub fn blend_transparent(b: f64, energy: [f64; 3]) -> [f64; 4] {
    blend_transparent_glow(b, energy.map(|c| b * c))
}

/// `blend_transparent` with the colored sum G: `(max(G, 0), clamp(B, 0, 1))`.
pub fn blend_transparent_glow(b: f64, glow: [f64; 3]) -> [f64; 4] {
    let [r, g, bl] = glow.map(|c| c.max(0.0));
    [r, g, bl, b.clamp(0.0, 1.0)]
}

/// The glow's colored sum `G = B Ce + tint = sum B_i Ce_i`, Ce the scene's energy color with its intensity.
pub fn glow(b: f64, tint: [f64; 3], energy: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|c| b * energy[c] + tint[c])
}

/// Samples a `w` x `w` row-major texture (rows from the top) bilinearly at texture coordinates `(u, v)` in
/// [0, 1], texel centers at `(i + 0.5) / w`, clamping at the edges: what a GPU linear sampler with
/// clamp-to-edge does.
pub fn sample_bilinear(texture: &[f64], w: u32, u: f64, v: f64) -> f64 {
    sample_bilinear_by(w, u, v, |k| texture[k])
}

/// `sample_bilinear` of the texture whose texel `k` (row-major) is `texel(k)`.
pub fn sample_bilinear_by(w: u32, u: f64, v: f64, texel: impl Fn(usize) -> f64) -> f64 {
    let w_i = w as i64;
    let x = u * w as f64 - 0.5;
    let y = v * w as f64 - 0.5;
    let x0 = x.floor();
    let y0 = y.floor();
    let fx = x - x0;
    let fy = y - y0;
    let at = |i: i64, j: i64| -> f64 {
        let i = i.clamp(0, w_i - 1);
        let j = j.clamp(0, w_i - 1);
        texel((j * w_i + i) as usize)
    };
    let (x0, y0) = (x0 as i64, y0 as i64);
    let top = at(x0, y0) * (1.0 - fx) + at(x0 + 1, y0) * fx;
    let bottom = at(x0, y0 + 1) * (1.0 - fx) + at(x0 + 1, y0 + 1) * fx;
    top * (1.0 - fy) + bottom * fy
}

/// Where (in units of `dir`) the ray from `eye` along `dir` meets the billboard's plane.
fn billboard_distance(billboard: &Billboard, eye: DVec3, dir: DVec3) -> f64 {
    (billboard.center - eye).dot(billboard.normal) / dir.dot(billboard.normal)
}

/// Texels whose clip differs from the pixel's by more than this share of the ray do not shade it.
pub const CLIP_MATCH: f64 = 0.05;

/// B and the tint at `(u, v)` interpolated bilinearly from the texels whose ray ends about where the pixel's
/// does (their clip, the share of S -> E before the first surface, within `CLIP_MATCH` of `clip`, the pixel's
/// own), their weights renormalised; where none does, the texel whose clip is nearest. Where objects stand, an
/// object's edge then cuts the glow as sharply as its pixels rather than in a staircase of texels: the glow on
/// either side is read from the texels on that side. Twin of the billboard shader's `sample_near_clip`.
pub fn sample_near_clip(
    texture: &BrightnessTexture,
    clips: &[f64],
    (u, v): (f64, f64),
    clip: f64,
) -> (f64, [f64; 3], f64) {
    let w = texture.resolution;
    let w_i = w as i64;
    let (x, y) = (u * w as f64 - 0.5, v * w as f64 - 0.5);
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let (x0, y0) = (x0 as i64, y0 as i64);
    let at = |i: i64, j: i64| (j.clamp(0, w_i - 1) * w_i + i.clamp(0, w_i - 1)) as usize;
    let corners = [
        (at(x0, y0), (1.0 - fx) * (1.0 - fy)),
        (at(x0 + 1, y0), fx * (1.0 - fy)),
        (at(x0, y0 + 1), (1.0 - fx) * fy),
        (at(x0 + 1, y0 + 1), fx * fy),
    ];
    // B undimmed by translucent objects, where the texture has it (what the glow's edge fades by), else B.
    let undimmed = |k: usize| match texture.undimmed.is_empty() {
        true => texture.values[k],
        false => texture.undimmed[k],
    };
    let (mut b, mut tint, mut edge, mut total) = (0.0, [0.0; 3], 0.0, 0.0);
    let mut nearest = (corners[0].0, f64::INFINITY);
    for (k, weight) in corners {
        let gap = (clips[k] - clip).abs();
        if gap < nearest.1 {
            nearest = (k, gap);
        }
        if gap <= CLIP_MATCH {
            b += weight * texture.values[k];
            (0..3).for_each(|c| tint[c] += weight * texture.tint[k][c]);
            edge += weight * undimmed(k);
            total += weight;
        }
    }
    if total > 0.0 {
        (b / total, tint.map(|x| x / total), edge / total)
    } else {
        let k = nearest.0;
        (texture.values[k], texture.tint[k], undimmed(k))
    }
}

/// What lies behind the glow in a composed frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Backdrop {
    /// The background color and the objects, opaque.
    Opaque,
    /// Transparent, the objects opaque over it.
    Transparent,
    /// Transparent, and the objects left out though they still hide the glow (a holdout).
    Holdout,
}

/// The frame the camera sees, RGBA, rows from the top: the background color everywhere, and over the
/// billboard the blend of B and the colored sum G = sum B_i Ce_i (both sampled bilinearly, as the GPU's pass
/// does) by the scene's blend, alpha 1. With `transparent`, the background is transparent and the billboard
/// carries associated (premultiplied) color G with alpha = min(B, 1) (`blend_transparent_glow`).
pub fn compose_frame(
    setup: &FrameSetup,
    texture: &BrightnessTexture,
    width: u32,
    height: u32,
    transparent: bool,
) -> Vec<[f64; 4]> {
    let backdrop = if transparent {
        Backdrop::Transparent
    } else {
        Backdrop::Opaque
    };
    compose_frame_over(setup, texture, (width, height), backdrop)
}

/// `compose_frame` over `backdrop`: the scene's objects (`super::objects`) drawn behind the glow as the
/// background is, each pixel's lit color where its ray meets one (the glow itself already ends there, the field
/// pass clips each texel's ray), then the billboard blended over that as over the background color.
pub fn compose_frame_over(
    setup: &FrameSetup,
    texture: &BrightnessTexture,
    size: (u32, u32),
    backdrop: Backdrop,
) -> Vec<[f64; 4]> {
    compose(setup, texture, size, backdrop, 1.0)
}

/// `compose_frame_over` for an HDR export: the opaque blends not clamped above 1 (below 0 still), as the GPU
/// renders with `HeadlessRenderer::set_unclamped`. A transparent frame is the same as `compose_frame_over`'s.
pub fn compose_frame_unclamped(
    setup: &FrameSetup,
    texture: &BrightnessTexture,
    size: (u32, u32),
    backdrop: Backdrop,
) -> Vec<[f64; 4]> {
    compose(setup, texture, size, backdrop, f64::INFINITY)
}

/// The frame's smoke as the GPU pass renders it (`reference::particles::SmokeImage`) over a field of
/// `resolution` texels, its rays ended by `objects` (`ObjectImage::of(setup)`): each smoke pixel's ray, through
/// the frame pixel it falls in, ends at the first opaque object, and past a translucent surface it meets first
/// the smoke is seen through the objects, dimmed by the light its field texel's ray keeps through them (the
/// texel the ray meets, nearest, as the GPU reads it). None without particles.
pub fn smoke_image(
    setup: &FrameSetup,
    objects: Option<&ObjectImage>,
    (width, height): (u32, u32),
    resolution: u32,
) -> Option<super::particles::SmokeImage> {
    let (scene, billboard) = (setup.scene, &setup.billboard);
    let forward = scene.camera.frame().forward;
    let crossings = setup.crossings_at(resolution);
    super::particles::SmokeImage::of(setup, [width, height], resolution, |x, y| {
        let eye = scene.camera.eye;
        let dir = (scene.camera).pixel_ray(x as f64 + 0.5, y as f64 + 0.5, width, height);
        let depth = |t: f64| t * dir.dot(forward);
        let until = objects
            .and_then(|o| o.hit_opaque(eye, dir))
            .map_or(f64::INFINITY, depth);
        let glass = objects
            .and_then(|o| o.hit_surface(eye, dir))
            .filter(|h| h.2)
            .map(|(t, _, _)| {
                let w = resolution;
                let behind =
                    (crossings.as_ref().zip(billboard.hit(eye, dir))).map_or(1.0, |(c, (u, v))| {
                        let texel = |s: f64| ((s * w as f64) as u32).min(w - 1) as usize;
                        c[3 * (texel(v) * w as usize + texel(u)) + 2] as f64
                    });
                super::particles::Glass {
                    depth: depth(t),
                    behind,
                }
            });
        (until, glass)
    })
}

/// The frame, its opaque blends clamped to [0, `top`].
fn compose(
    setup: &FrameSetup,
    texture: &BrightnessTexture,
    (width, height): (u32, u32),
    backdrop: Backdrop,
    top: f64,
) -> Vec<[f64; 4]> {
    let (scene, billboard, reach) = (setup.scene, &setup.billboard, setup.reach);
    let transparent = backdrop != Backdrop::Opaque;
    let [r, g, b] = scene.colors.background;
    let clear = if transparent {
        [0.0; 4]
    } else {
        [r, g, b, 1.0]
    };
    // Held out, the objects are not drawn but still hide the glow in front of them.
    let objects = ObjectImage::of(setup);
    // The clips the billboard matches each pixel's own surface against: up to the first surface of any object
    // (a translucent one's edge guides the glow blended for it as an opaque one's guides the glow it ends).
    let surfaces = match setup.translucent() {
        true => &scene.objects[..],
        false => setup.clip_objects(),
    };
    let clips = clip_fractions(
        surfaces,
        scene.camera.eye,
        billboard,
        reach,
        texture.resolution,
    );
    let drawn = backdrop != Backdrop::Holdout;
    // The particles' smoke, its rays ended by the objects; the back image under the glow, the front one over it.
    let smoke = smoke_image(setup, objects.as_ref(), (width, height), texture.resolution);
    let glared = scene.glare.map(|g| super::glare::apply(texture, &g));
    let texture = glared.as_ref().unwrap_or(texture);
    let mut pixels = vec![clear; width as usize * height as usize];
    pixels
        .par_chunks_mut(width.max(1) as usize)
        .enumerate()
        .for_each(|(y, row)| {
            for (x, out) in row.iter_mut().enumerate() {
                let dir = scene
                    .camera
                    .pixel_ray(x as f64 + 0.5, y as f64 + 0.5, width, height);
                let hit = objects
                    .as_ref()
                    .and_then(|o| o.hit_surface(scene.camera.eye, dir));
                let under = match hit {
                    Some((_, [r, g, b], _)) if drawn => [r, g, b, 1.0],
                    _ => clear,
                };
                let [front, back] = smoke
                    .as_ref()
                    .map_or([[0.0, 0.0, 0.0, 1.0]; 2], |s| s.at(x as u32, y as u32));
                let under = super::particles::smoke_over(back, under);
                *out = under;
                if let Some((u, v)) = billboard.hit(scene.camera.eye, dir) {
                    // Only the opaque objects end the glow (`setup.clip_objects`); without them, none.
                    let ends = clips.as_ref().map(|_| ());
                    // B, the tint, and what the glow's edge fades by (B, or B undimmed by translucent objects).
                    let (b, tint, edge) = match (&ends, hit) {
                        (None, _) => {
                            let b = sample_bilinear(&texture.values, texture.resolution, u, v);
                            let tint = std::array::from_fn(|c| {
                                sample_bilinear_by(texture.resolution, u, v, |k| texture.tint[k][c])
                            });
                            (b, tint, b)
                        }
                        // An opaque object in front of the billboard hides the glow at this pixel (a
                        // translucent one lets through the glow blended for it).
                        (Some(_), Some((t, _, false)))
                            if t < billboard_distance(billboard, scene.camera.eye, dir) =>
                        {
                            (0.0, [0.0; 3], 0.0)
                        }
                        (Some(_), hit) => {
                            // The pixel's own clip: where along S -> E its ray meets the object behind the
                            // billboard (1: none).
                            let clip = hit.map_or(1.0, |(t, _, _)| {
                                let tau = t / billboard_distance(billboard, scene.camera.eye, dir);
                                ((tau - 1.0) / (reach.nu - 1.0)).clamp(0.0, 1.0)
                            });
                            sample_near_clip(texture, clips.as_deref().unwrap_or(&[]), (u, v), clip)
                        }
                    };
                    let fade = crate::scene::edge_fade(edge, scene.colors.cutoff)
                        * crate::geometry::edge_window(u, v, billboard.edge);
                    let (b, tint) = (b * fade, tint.map(|t| t * fade));
                    let g = glow(b, tint, scene.colors.energy_color());
                    *out = if transparent {
                        // Premultiplied "over" what lies behind (transparent, or an opaque object).
                        let [r, g, bl, a] = blend_transparent_glow(b, g);
                        [
                            r + (1.0 - a) * under[0],
                            g + (1.0 - a) * under[1],
                            bl + (1.0 - a) * under[2],
                            a + (1.0 - a) * under[3],
                        ]
                    } else {
                        let cb = [under[0], under[1], under[2]];
                        let [r, g, b] = match scene.colors.blend {
                            Blend::Papers => papers_unclamped(b, g, cb),
                            Blend::Over => over_unclamped(b, g, cb),
                        }
                        .map(|c| c.clamp(0.0, top));
                        [r, g, b, under[3]]
                    };
                }
                *out = super::particles::smoke_over(front, *out);
            }
        });
    pixels
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blend_limits() {
        let ce = [0.2, 0.5, 1.0];
        let cb = [0.1, 0.1, 0.3];
        assert_eq!(blend(0.0, ce, cb), cb);
        assert_eq!(blend(1.0, ce, cb), ce);
        // B well above 1 blows out: every channel with Ce > Cb saturates.
        assert_eq!(blend(50.0, ce, cb), [1.0, 1.0, 1.0]);
        // A channel where Cb > Ce goes toward 0, clamped there.
        assert_eq!(
            blend(5.0, [0.0, 0.0, 0.0], [0.5, 0.5, 0.5]),
            [0.0, 0.0, 0.0]
        );
    }

    #[test]
    fn transparent_export_composites_like_the_blend() {
        let ce = [0.2, 0.5, 1.0];
        for b in [0.0, 0.3, 1.0] {
            for cb in [[0.0, 0.0, 0.0], [0.9, 0.4, 0.1]] {
                // Associated alpha: "over" adds the color as it is.
                let [r, g, bl, a] = blend_transparent(b, ce);
                let over: [f64; 3] = std::array::from_fn(|c| [r, g, bl][c] + cb[c] * (1.0 - a));
                let want = blend(b, ce, cb);
                assert!(
                    over.iter().zip(want).all(|(x, y)| (x - y).abs() < 1e-12),
                    "{b} {cb:?}"
                );
            }
        }
        // Over black, blown-out values too, once the display clamps them; unclamped they keep B Ce.
        let [r, g, bl, a] = blend_transparent(3.0, ce);
        assert_eq!(a, 1.0);
        assert_eq!([r, g, bl], [0.6000000000000001, 1.5, 3.0]);
        assert_eq!(
            [r, g, bl].map(|c| c.clamp(0.0, 1.0)),
            blend(3.0, ce, [0.0; 3])
        );
    }

    #[test]
    fn the_over_blend_is_the_transparent_export_composited_for_every_b() {
        let ce = [0.6, 0.9, 1.0];
        for cb in [[0.0, 0.8, 0.1], [0.9, 0.4, 0.1], [0.0; 3], [1.0; 3]] {
            for b in [-0.5, 0.0, 0.25, 0.7, 1.0, 1.3, 4.0, 40.0] {
                let [r, g, bl, a] = blend_transparent(b, ce);
                let composited: [f64; 3] =
                    std::array::from_fn(|c| ([r, g, bl][c] + cb[c] * (1.0 - a)).clamp(0.0, 1.0));
                assert_eq!(blend_over(b, ce, cb), composited, "B {b} over {cb:?}");
                // The papers' blend wherever 0 <= B <= 1.
                if (0.0..=1.0).contains(&b) {
                    let papers = blend(b, ce, cb);
                    assert!((0..3).all(|c| (papers[c] - composited[c]).abs() < 1e-12));
                }
            }
        }
        // Where the papers' blend subtracts the background, "over" keeps the core white-hot: the default
        // light-blue core over green turns magenta in the papers' blend (by hand: 0.3 x 2, 1 - 0.45 x 2, 1).
        let (blue, green) = ([0.3, 0.55, 1.0], [0.0, 1.0, 0.0]);
        let papers = blend(2.0, blue, green);
        assert!(
            (papers[0] - 0.6).abs() < 1e-12 && (papers[1] - 0.1).abs() < 1e-12 && papers[2] == 1.0
        );
        assert_eq!(blend_over(2.0, blue, green), [0.6, 1.0, 1.0]);
    }

    #[test]
    fn bilinear_hits_texel_centers_and_interpolates() {
        let tex = [0.0, 1.0, 2.0, 3.0];
        assert!((sample_bilinear(&tex, 2, 0.25, 0.25) - 0.0).abs() < 1e-12);
        assert!((sample_bilinear(&tex, 2, 0.75, 0.75) - 3.0).abs() < 1e-12);
        assert!((sample_bilinear(&tex, 2, 0.5, 0.5) - 1.5).abs() < 1e-12);
        // Clamped beyond the outer texel centers.
        assert!((sample_bilinear(&tex, 2, 0.0, 0.0) - 0.0).abs() < 1e-12);
        assert!((sample_bilinear(&tex, 2, 1.0, 1.0) - 3.0).abs() < 1e-12);
    }
}
