//! Measures the texel-area gain of the exact minimal cone over the paper's cone on
//! random light and camera configurations; prints the table of the crate docs.
//!
//! `cargo run --release -p shadowmap-paraboloid --example ipsm_table`
#![allow(clippy::print_stdout)]

use glam::Vec3;
use shadowmap_frustum::{Camera, DepthBounds, Light, Projection};
use shadowmap_paraboloid::{ConeFit, IpsmOptions, IpsmPlan};

/// xorshift64*: deterministic, dependency-free.
struct Rng(u64);

impl Rng {
    fn next_f32(&mut self) -> f32 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let x = self.0.wrapping_mul(0x2545_F491_4F6C_DD1D);
        (x >> 40) as f32 / (1u64 << 24) as f32
    }
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.next_f32()
    }
    fn unit(&mut self) -> Vec3 {
        let z = self.range(-1.0, 1.0);
        let phi = self.range(0.0, core::f32::consts::TAU);
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    }
}

fn percentile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let i = ((sorted.len() - 1) as f64 * p).round() as usize;
    sorted[i]
}

fn main() {
    const CONFIGS: usize = 2000;
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let mut gains_all = Vec::new();
    let mut gains_single = Vec::new();
    let (mut turned, mut both_dual, mut both_single) = (0usize, 0usize, 0usize);
    let mut done = 0;
    while done < CONFIGS {
        let eye = Vec3::new(
            rng.range(-50.0, 50.0),
            rng.range(0.0, 20.0),
            rng.range(-50.0, 50.0),
        );
        let forward = rng.unit();
        let fov = rng.range(30.0, 100.0).to_radians();
        let aspect = rng.range(1.0, 2.4);
        let Ok(camera) = Camera::look_to(
            eye,
            forward,
            Vec3::Y,
            Projection::perspective(fov, aspect, 0.1, 500.0),
        ) else {
            continue;
        };
        let min = 0.1 * 1000f32.powf(rng.next_f32());
        let max = (min * rng.range(1.5, 50.0)).min(500.0);
        let bounds = DepthBounds { min, max };
        let position = eye
            + Vec3::new(
                rng.range(-200.0, 200.0),
                rng.range(-200.0, 200.0),
                rng.range(-200.0, 200.0),
            );
        let light = Light::Point {
            position,
            range: 5000.0,
        };
        let exact = IpsmPlan::new(&light, &camera, Some(bounds), &IpsmOptions::default());
        let paper = IpsmPlan::new(
            &light,
            &camera,
            Some(bounds),
            &IpsmOptions::default().with_fit(ConeFit::Paper),
        );
        let (Ok(exact), Ok(paper)) = (exact, paper) else {
            continue;
        };
        done += 1;
        let gain = (f64::from(paper.zoom()) / f64::from(exact.zoom())).powi(2);
        gains_all.push(gain);
        match (paper.is_single(), exact.is_single()) {
            (false, true) => turned += 1,
            (false, false) => both_dual += 1,
            (true, true) => both_single += 1,
            (true, false) => panic!("the exact fit made a single case dual"),
        }
        if exact.is_single() {
            gains_single.push(gain);
        }
    }
    let stats = |g: &mut Vec<f64>| {
        g.sort_by(f64::total_cmp);
        let mean = g.iter().sum::<f64>() / g.len() as f64;
        (mean, percentile(g, 0.5), percentile(g, 0.95), g.len())
    };
    let (m_all, med_all, p95_all, n_all) = stats(&mut gains_all);
    let (m_s, med_s, p95_s, n_s) = stats(&mut gains_single);
    let pct = |n: usize| 100.0 * n as f64 / CONFIGS as f64;
    println!("| configurations | count | mean gain | median gain | p95 gain |");
    println!("|---|---|---|---|---|");
    println!("| all | {n_all} | {m_all:.3} | {med_all:.3} | {p95_all:.3} |");
    println!("| exact fit single | {n_s} | {m_s:.3} | {med_s:.3} | {p95_s:.3} |");
    println!();
    println!("| outcome | fraction |");
    println!("|---|---|");
    println!(
        "| dual with the paper's cone, single with the exact cone | {:.1}% |",
        pct(turned)
    );
    println!("| single with both | {:.1}% |", pct(both_single));
    println!(
        "| dual with both (light inside the truncated frustum) | {:.1}% |",
        pct(both_dual)
    );
}
