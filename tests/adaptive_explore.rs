use energywave::bench::RenderError;
use energywave::integrate::Integrator;
use energywave::reference;
use energywave::scene::Scene;
use std::path::Path;
use std::time::Instant;

#[test]
#[ignore]
fn explore() {
    for name in ["torus_r0.9_t5.1", "bezier_b5.0"] {
        let mut scene =
            Scene::load(&Path::new("assets/scenes").join(format!("{name}.toml"))).unwrap();
        scene.billboard.resolution = 64;
        let bb = scene.place_billboard(1.0);
        let mut r = scene.clone();
        r.integration.integrator = Integrator::Simpson;
        r.integration.divisions = 16384;
        let reference = reference::render_brightness(&r, &bb).values;
        for tol in [1e-4, 1e-5, 1e-6] {
            let mut a = scene.clone();
            a.integration.tolerance = tol;
            let t = Instant::now();
            let img: Vec<f32> = reference::render_brightness(&a, &bb)
                .values
                .iter()
                .map(|&v| v as f32)
                .collect();
            let e = RenderError::of(&img, 64, 1, &reference);
            let (k, worst) = img
                .iter()
                .zip(&reference)
                .enumerate()
                .map(|(k, (a, b))| (k, ((*a as f64).clamp(0.0, 1.0) - b.clamp(0.0, 1.0)).abs()))
                .max_by(|a, b| a.1.total_cmp(&b.1))
                .unwrap();
            eprintln!(
                "{name} tol {tol:e}: {e:?} worst texel ({}, {}) {worst:e} {:.2}s",
                k % 64,
                k / 64,
                t.elapsed().as_secs_f64()
            );
        }
    }
}
