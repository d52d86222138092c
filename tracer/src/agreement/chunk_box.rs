//! What the screens of every primitive kind share: Morton order, and the box of a chunk of points that a ray's
//! line must come near for the chunk to hold a candidate.

/// The box of a chunk's points: center and half extents.
#[derive(Clone, Copy, Debug)]
pub(super) struct ChunkBox {
    center: [f64; 3],
    half: [f64; 3],
}

impl ChunkBox {
    /// The box of the points `(x[i], y[i], z[i])`.
    pub(super) fn of(x: &[f64], y: &[f64], z: &[f64]) -> Self {
        let span = |v: &[f64]| v.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| (lo.min(x), hi.max(x)));
        let ((x0, x1), (y0, y1), (z0, z1)) = (span(x), span(y), span(z));
        Self {
            center: [0.5 * (x0 + x1), 0.5 * (y0 + y1), 0.5 * (z0 + z1)],
            half: [0.5 * (x1 - x0), 0.5 * (y1 - y0), 0.5 * (z1 - z0)],
        }
    }

    /// True when the line `o + s·n` (`n` a unit vector) meets the box widened by `widen(far)` on every side, `far`
    /// bounding the distance from `o` to any point of the box.
    pub(super) fn meets_line(&self, o: [f64; 3], n: [f64; 3], widen: impl Fn(f64) -> f64) -> bool {
        let rel: [f64; 3] = std::array::from_fn(|k| o[k] - self.center[k]);
        let far = (rel[0] * rel[0] + rel[1] * rel[1] + rel[2] * rel[2]).sqrt()
            + (self.half[0] * self.half[0] + self.half[1] * self.half[1] + self.half[2] * self.half[2]).sqrt();
        let widen = widen(far);
        let (mut enter, mut exit) = (f64::NEG_INFINITY, f64::INFINITY);
        #[allow(clippy::needless_range_loop)] // k indexes four per-axis arrays alike
        for k in 0..3 {
            let (lo, hi) = (-self.half[k] - widen - rel[k], self.half[k] + widen - rel[k]);
            if n[k] == 0.0 {
                if lo > 0.0 || hi < 0.0 {
                    return false;
                }
            } else {
                let (t0, t1) = (lo / n[k], hi / n[k]);
                enter = enter.max(t0.min(t1));
                exit = exit.min(t0.max(t1));
            }
        }
        enter <= exit
    }
}

/// A 30-bit Morton code of a point of the box `lo..lo + 1/scale`.
fn morton(p: [f64; 3], lo: [f64; 3], scale: [f64; 3]) -> u32 {
    let spread = |x: u32| {
        let mut x = x & 0x3ff;
        x = (x | (x << 16)) & 0x0300_00ff;
        x = (x | (x << 8)) & 0x0300_f00f;
        x = (x | (x << 4)) & 0x030c_30c3;
        (x | (x << 2)) & 0x0924_9249
    };
    let q = |k: usize| ((p[k] - lo[k]) * scale[k]).clamp(0.0, 1023.0) as u32;
    spread(q(0)) | (spread(q(1)) << 1) | (spread(q(2)) << 2)
}

/// The Morton order of `points`: their indices sorted by code in the points' bounding box, ties by index.
pub(super) fn morton_order(points: &[[f64; 3]]) -> Vec<u32> {
    let lo: [f64; 3] = std::array::from_fn(|k| points.iter().fold(f64::INFINITY, |m, c| m.min(c[k])));
    let hi: [f64; 3] = std::array::from_fn(|k| points.iter().fold(f64::NEG_INFINITY, |m, c| m.max(c[k])));
    let scale: [f64; 3] = std::array::from_fn(|k| if hi[k] > lo[k] { 1023.0 / (hi[k] - lo[k]) } else { 0.0 });
    let mut order: Vec<u32> = (0..points.len() as u32).collect();
    order.sort_by_key(|&i| (morton(points[i as usize], lo, scale), i));
    order
}
