//! The 3-D FFT and the circulant embedding of the volumetric brute force.

use std::sync::Arc;

use rustfft::num_complex::Complex64 as C;
use rustfft::{Fft, FftPlanner};

use super::{V3, VolumeGrid};

/// In-place 3-D FFT of a row-major `[z][y][x]` array (forward `e^{−2πi m·n/N}`, unnormalised).
pub struct Fft3 {
    n: [usize; 3],
    ffts: [Arc<dyn Fft<f64>>; 3],
    scratch: Vec<C>,
    lines: Vec<C>,
}

impl Fft3 {
    /// A forward (or, with `inverse`, backward) transform of size `n`.
    #[must_use]
    pub fn new(n: [usize; 3], inverse: bool) -> Self {
        let mut planner = FftPlanner::new();
        let ffts = n.map(|m| {
            if inverse {
                planner.plan_fft_inverse(m)
            } else {
                planner.plan_fft_forward(m)
            }
        });
        let scratch_len = ffts
            .iter()
            .map(|f| f.get_inplace_scratch_len())
            .max()
            .unwrap_or(0);
        Self {
            n,
            ffts,
            scratch: vec![C::new(0.0, 0.0); scratch_len],
            lines: vec![C::new(0.0, 0.0); n[0] * n[1].max(n[2])],
        }
    }

    /// Transforms `buf` (`n_x n_y n_z` values) in place.
    pub fn run(&mut self, buf: &mut [C]) {
        let all: Vec<usize> = (0..self.n[0].max(self.n[1])).collect();
        self.run_pruned(buf, &all[..self.n[0]], &all[..self.n[1]]);
    }

    /// Transforms `buf` in place, but only the outputs with x-index in `xs` and y-index in `ys`
    /// (every z) are valid: the y-pass runs on the columns `xs` only, the z-pass on `xs × ys`.
    /// The brute force reads the transform only at its light modes, a small block around 0.
    pub fn run_pruned(&mut self, buf: &mut [C], xs: &[usize], ys: &[usize]) {
        let [nx, ny, nz] = self.n;
        if nx > 1 {
            self.ffts[0].process_with_scratch(buf, &mut self.scratch);
        }
        if ny > 1 {
            // Per z-plane: gather the y-lines of the kept columns, transform, scatter.
            let lines = &mut self.lines[..xs.len() * ny];
            for z in 0..nz {
                let plane = &mut buf[z * nx * ny..(z + 1) * nx * ny];
                for y in 0..ny {
                    for (j, &x) in xs.iter().enumerate() {
                        lines[j * ny + y] = plane[y * nx + x];
                    }
                }
                self.ffts[1].process_with_scratch(lines, &mut self.scratch);
                for y in 0..ny {
                    for (j, &x) in xs.iter().enumerate() {
                        plane[y * nx + x] = lines[j * ny + y];
                    }
                }
            }
        }
        if nz > 1 {
            // Per kept y: gather the z-lines of the kept columns.
            let lines = &mut self.lines[..xs.len() * nz];
            for &y in ys {
                for z in 0..nz {
                    for (j, &x) in xs.iter().enumerate() {
                        lines[j * nz + z] = buf[(z * ny + y) * nx + x];
                    }
                }
                self.ffts[2].process_with_scratch(lines, &mut self.scratch);
                for z in 0..nz {
                    for (j, &x) in xs.iter().enumerate() {
                        buf[(z * ny + y) * nx + x] = lines[j * nz + z];
                    }
                }
            }
        }
    }
}

/// Signed frequency index of DFT bin `i` (`−n/2 < s ≤ n/2`).
fn signed(i: usize, n: usize) -> i64 {
    crate::brute::signed(i, n)
}

/// Circulant eigenvalues of a sampled stationary covariance `cov(ξ)` on `grid` (min-image
/// separations), clamped at 0.
#[must_use]
pub fn circulant_spectrum(grid: &VolumeGrid, cov: &dyn Fn(V3) -> f64) -> Vec<f64> {
    let [nx, ny, nz] = grid.n;
    let mut buf = vec![C::new(0.0, 0.0); grid.len()];
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                let r = [
                    signed(x, nx) as f64 * grid.d[0],
                    signed(y, ny) as f64 * grid.d[1],
                    signed(z, nz) as f64 * grid.d[2],
                ];
                buf[(z * ny + y) * nx + x] = C::new(cov(r), 0.0);
            }
        }
    }
    Fft3::new(grid.n, false).run(&mut buf);
    buf.iter().map(|c| c.re.max(0.0)).collect()
}
