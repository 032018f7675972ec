//! The glare pass's f64 twin (`shaders/glare.wgsl`): a fog glow in the billboard's plane. Each texel's excess
//! over the threshold, compressed, `E = max(B - T, 0) / (1 + max(B - T, 0))`, in the texel's own color (its
//! tint scaled alike, `E tint / B`), is
//! blurred by a separable Gaussian (rows, then columns, edges clamped) and added back `strength` times:
//! `B' = B + s blur(E)`, `tint' = tint + s blur(E tint / B)`. The blends then take the glare as more glow.

use super::field_pass::BrightnessTexture;
use crate::scene::Glare;

/// The excess of texel `k` over the threshold in each layer: B's, and the tint's in the texel's color.
fn excess(texture: &BrightnessTexture, threshold: f64, k: usize) -> [f64; 4] {
    let b = texture.values[k];
    if b <= threshold {
        return [0.0; 4];
    }
    // Compressed, E / (1 + E): a core a thousand times over the threshold glares about as much as one twice
    // over it, so one default suits a faint ring and a blinding beam alike.
    let e = b - threshold;
    let e = e / (1.0 + e);
    let t = texture.tint[k];
    [e, e * t[0] / b, e * t[1] / b, e * t[2] / b]
}

/// `texture` with the glare added.
pub fn apply(texture: &BrightnessTexture, glare: &Glare) -> BrightnessTexture {
    let w = texture.resolution as usize;
    let weights = glare.kernel(texture.resolution);
    let r = (weights.len() / 2) as i64;
    let at = |i: i64| i.clamp(0, w as i64 - 1) as usize;
    let source: Vec<[f64; 4]> = (0..w * w)
        .map(|k| excess(texture, glare.threshold, k))
        .collect();
    let blur = |input: &[[f64; 4]], step: (usize, usize)| -> Vec<[f64; 4]> {
        (0..w * w)
            .map(|k| {
                let (x, y) = ((k % w) as i64, (k / w) as i64);
                let mut sum = [0.0; 4];
                for (o, weight) in (-r..=r).zip(&weights) {
                    let (xi, yi) = (at(x + o * step.0 as i64), at(y + o * step.1 as i64));
                    let v = input[yi * w + xi];
                    (0..4).for_each(|l| sum[l] += weight * v[l]);
                }
                sum
            })
            .collect()
    };
    let blurred = blur(&blur(&source, (1, 0)), (0, 1));
    let s = glare.strength;
    BrightnessTexture {
        resolution: texture.resolution,
        values: (texture.values.iter().zip(&blurred))
            .map(|(b, g)| b + s * g[0])
            .collect(),
        tint: (texture.tint.iter().zip(&blurred))
            .map(|(t, g)| [t[0] + s * g[1], t[1] + s * g[2], t[2] + s * g[3]])
            .collect(),
        // B undimmed by translucent objects glares as B does, from its own excess.
        undimmed: match texture.undimmed.is_empty() {
            true => Vec::new(),
            false => {
                let own = BrightnessTexture {
                    resolution: texture.resolution,
                    values: texture.undimmed.clone(),
                    tint: texture.tint.clone(),
                    undimmed: Vec::new(),
                };
                apply(&own, glare).values
            }
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn texture(w: u32, f: impl Fn(usize, usize) -> (f64, [f64; 3])) -> BrightnessTexture {
        let n = w as usize;
        let (values, tint) = (0..n * n).map(|k| f(k % n, k / n)).unzip();
        BrightnessTexture {
            resolution: w,
            values,
            tint,
            undimmed: Vec::new(),
        }
    }

    #[test]
    fn the_separable_blur_is_the_two_dimensional_gaussian_by_brute_force() {
        let glare = Glare {
            threshold: 0.5,
            size: 0.06,
            strength: 0.8,
        };
        let w = 40u32;
        let t = texture(w, |x, y| {
            let d2 = (x as f64 - 17.0).powi(2) + (y as f64 - 22.0).powi(2);
            let b = 3.0 * (-d2 / 8.0).exp() + 0.1;
            (b, [0.2 * b, -0.1 * b, 0.05 * x as f64])
        });
        let out = apply(&t, &glare);
        // The 2D convolution written out, with the unnormalised Gaussian normalised over the same square.
        let sigma = glare.size * w as f64;
        let r = (3.0 * sigma).ceil() as i64;
        let n = w as i64;
        let norm: f64 = (-r..=r)
            .map(|k| (-(k * k) as f64 / (2.0 * sigma * sigma)).exp())
            .sum::<f64>()
            .powi(2);
        for &(x, y) in &[(17, 22), (0, 0), (39, 5), (20, 20), (25, 30)] {
            let mut want = [0.0; 4];
            for dy in -r..=r {
                for dx in -r..=r {
                    let g = (-((dx * dx + dy * dy) as f64) / (2.0 * sigma * sigma)).exp() / norm;
                    let (xi, yi) = ((x + dx).clamp(0, n - 1), (y + dy).clamp(0, n - 1));
                    let k = (yi * n + xi) as usize;
                    let b = t.values[k];
                    if b > glare.threshold {
                        let e = (b - glare.threshold) / (1.0 + b - glare.threshold);
                        want[0] += g * e;
                        for c in 0..3 {
                            want[c + 1] += g * e * t.tint[k][c] / b;
                        }
                    }
                }
            }
            let k = (y * n + x) as usize;
            assert!((out.values[k] - (t.values[k] + 0.8 * want[0])).abs() < 1e-12);
            for c in 0..3 {
                assert!((out.tint[k][c] - (t.tint[k][c] + 0.8 * want[c + 1])).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn below_the_threshold_nothing_glares_and_the_glare_keeps_its_energy() {
        let glare = Glare {
            threshold: 1.0,
            size: 0.05,
            strength: 1.0,
        };
        let dim = texture(32, |x, _| (0.9 * x as f64 / 31.0, [0.1, 0.0, 0.0]));
        assert_eq!(apply(&dim, &glare), dim);
        // One hot texel in the middle: the excess, compressed to 4 / (1 + 4), spreads but keeps its sum (no
        // edge reached).
        let hot = texture(64, |x, y| {
            (if (x, y) == (32, 32) { 5.0 } else { 0.0 }, [0.0; 3])
        });
        let out = apply(&hot, &glare);
        let added: f64 = out.values.iter().sum::<f64>() - 5.0;
        assert!((added - 0.8).abs() < 1e-12, "{added}");
        assert!(
            out.values[32 * 64 + 40] > 0.0 && out.values[32 * 64 + 40] < out.values[32 * 64 + 33]
        );
    }
}
