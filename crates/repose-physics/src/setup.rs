//! Initial conditions: radii drawn from the scene's distribution and a
//! random non-overlapping placement, both from a seeded ChaCha8 stream.
//!
//! The conversion from random bits to numbers is written here (not taken
//! from a distribution crate) so that the same seed gives the same grains
//! whatever versions of those crates a build resolves.

use rand_chacha::ChaCha8Rng;
use rand_core::{RngCore, SeedableRng};
use repose_engine::dim::Vector;
use serde::{Deserialize, Serialize};

/// The scene's random stream; its state serialises, so a saved run goes
/// on drawing the numbers it would have drawn.
#[derive(Serialize, Deserialize)]
pub struct Stream(ChaCha8Rng);

impl Stream {
    pub fn new(seed: u64) -> Self {
        Stream(ChaCha8Rng::seed_from_u64(seed))
    }

    /// Uniform in `[0, 1)` with 53 random bits.
    pub fn uniform(&mut self) -> f64 {
        (self.0.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Standard normal by the Box–Muller transform (one value per call).
    pub fn normal(&mut self) -> f64 {
        let u1 = 1.0 - self.uniform(); // (0, 1]
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }

    /// A draw from the Gaussian of `mean` and `sd`, drawn again while
    /// outside `[min, max]` (resampled, not clamped); `mean` itself when
    /// `sd` is zero.
    pub fn cut_normal(&mut self, mean: f64, sd: f64, min: f64, max: f64) -> f64 {
        if sd == 0.0 {
            return mean;
        }
        loop {
            let x = mean + sd * self.normal();
            if x >= min && x <= max {
                return x;
            }
        }
    }
}

/// Mass of a sphere of radius `a` and density `rho` (the Hertz law is the 3D one).
pub fn sphere_mass(rho: f64, a: f64) -> f64 {
    4.0 / 3.0 * std::f64::consts::PI * rho * a * a * a
}

/// Random sequential addition of discs with the given radii into the
/// column `0 ≤ x ≤ width`, `y ≥ 0`, at about the given packing fraction:
/// each disc is tried at random points until it overlaps nothing; when a
/// disc finds no room after many tries the column grows taller.
pub fn random_column(
    stream: &mut Stream,
    radii: &[f64],
    width: f64,
    fraction: f64,
) -> Vec<Vector<2>> {
    let area: f64 = radii.iter().map(|r| std::f64::consts::PI * r * r).sum();
    let mut height =
        (area / (fraction * width)).max(2.0 * radii.iter().copied().fold(0.0, f64::max));
    let rmax = radii.iter().copied().fold(0.0, f64::max);
    let cell = 2.0 * rmax;
    let cols = ((width / cell).ceil() as usize).max(1);
    let mut grid: Vec<Vec<u32>> = Vec::new();
    let mut placed: Vec<Vector<2>> = Vec::with_capacity(radii.len());
    let cell_of = |x: &Vector<2>| {
        let cx = ((x.x / cell) as usize).min(cols - 1);
        let cy = (x.y / cell).max(0.0) as usize;
        (cx, cy)
    };
    for (i, &r) in radii.iter().enumerate() {
        let mut tries = 0;
        loop {
            tries += 1;
            if tries > 200 {
                height *= 1.1;
                tries = 0;
            }
            let x = r + (width - 2.0 * r) * stream.uniform();
            let y = r + (height - 2.0 * r).max(0.0) * stream.uniform();
            let candidate = Vector::<2>::new(x, y);
            let (cx, cy) = cell_of(&candidate);
            let mut free = true;
            'search: for gy in cy.saturating_sub(1)..=cy + 1 {
                for gx in cx.saturating_sub(1)..=(cx + 1).min(cols - 1) {
                    let Some(bucket) = grid.get(gy * cols + gx) else {
                        continue;
                    };
                    for &j in bucket {
                        let other = placed[j as usize];
                        let reach = r + radii[j as usize];
                        if (candidate - other).norm_squared() < reach * reach {
                            free = false;
                            break 'search;
                        }
                    }
                }
            }
            if free {
                let needed = (cy + 2) * cols;
                if grid.len() < needed {
                    grid.resize(needed, Vec::new());
                }
                grid[cy * cols + cx].push(i as u32);
                placed.push(candidate);
                break;
            }
        }
    }
    placed
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_follow_the_cut_gaussian() {
        let mut s = Stream::new(7);
        let r: Vec<f64> = (0..20_000)
            .map(|_| s.cut_normal(0.1, 0.02, 0.07, 0.13))
            .collect();
        assert!(r.iter().all(|&x| (0.07..=0.13).contains(&x)));
        let mean = r.iter().sum::<f64>() / r.len() as f64;
        assert!((mean - 0.1).abs() < 1e-3, "{mean}");
        // the cut at ±1.5 sd lowers the spread: sd of the truncated normal ≈ 0.7427 σ
        let sd = (r.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / r.len() as f64).sqrt();
        assert!((sd - 0.7427 * 0.02).abs() < 3e-4, "{sd}");
    }

    #[test]
    fn placement_never_overlaps_and_stays_in_the_column() {
        let mut s = Stream::new(3);
        let radii: Vec<f64> = (0..400)
            .map(|_| s.cut_normal(0.1, 0.02, 0.07, 0.13))
            .collect();
        let pos = random_column(&mut s, &radii, 4.0, 0.35);
        for i in 0..pos.len() {
            assert!(pos[i].x >= radii[i] && pos[i].x <= 4.0 - radii[i]);
            assert!(pos[i].y >= radii[i]);
            for j in 0..i {
                assert!((pos[i] - pos[j]).norm() >= radii[i] + radii[j]);
            }
        }
    }

    #[test]
    fn same_seed_same_stream() {
        let (mut a, mut b) = (Stream::new(11), Stream::new(11));
        for _ in 0..100 {
            assert_eq!(a.uniform().to_bits(), b.uniform().to_bits());
        }
    }
}
