//! The chapter's overconfidence world (docs/models.md#tempering): a straight corridor with door
//! frames, an exact ray caster against its wall segments, and rasterization into an occupancy
//! grid (row 0 = lowest y), for building distance fields from a right and a wrong map.

/// A wall segment, metres.
#[derive(Clone, Copy, Debug)]
pub struct Segment {
    /// Start point.
    pub a: (f64, f64),
    /// End point.
    pub b: (f64, f64),
}

/// A corridor world: segments and the bounding box of the map.
#[derive(Clone, Debug)]
pub struct World {
    /// Walls.
    pub segments: Vec<Segment>,
    /// Map extent, metres: (min x, min y, max x, max y).
    pub bounds: (f64, f64, f64, f64),
}

/// A 12 m × 2 m corridor along x (y from 0 to 2) starting at x = 0, with door frames: a 0.9 m
/// doorway every 2.5 m on alternate sides, each framed by 0.12 m jambs protruding into the
/// corridor, and a recess of 0.3 m behind the door. The end walls close it.
pub fn corridor() -> World {
    let (len, width) = (12.0, 2.0);
    let mut s = vec![
        Segment {
            a: (0.0, 0.0),
            b: (0.0, width),
        },
        Segment {
            a: (len, 0.0),
            b: (len, width),
        },
    ];
    // Walls with gaps at the doors; each door has jambs and a recess.
    for side in [0.0, width] {
        let inward = if side == 0.0 { 1.0 } else { -1.0 };
        let mut x = 0.0;
        let mut door_x = if side == 0.0 { 1.3 } else { 2.55 };
        while door_x + 0.9 < len {
            s.push(Segment {
                a: (x, side),
                b: (door_x, side),
            });
            let (d0, d1) = (door_x, door_x + 0.9);
            // jambs into the corridor
            s.push(Segment {
                a: (d0, side),
                b: (d0, side + inward * 0.12),
            });
            s.push(Segment {
                a: (d1, side),
                b: (d1, side + inward * 0.12),
            });
            // recess behind the (closed) door
            let back = side - inward * 0.3;
            s.push(Segment {
                a: (d0, side),
                b: (d0, back),
            });
            s.push(Segment {
                a: (d1, side),
                b: (d1, back),
            });
            s.push(Segment {
                a: (d0, back),
                b: (d1, back),
            });
            x = d1;
            door_x += 2.5;
        }
        s.push(Segment {
            a: (x, side),
            b: (len, side),
        });
    }
    World {
        segments: s,
        bounds: (-0.5, -0.5, len + 0.5, width + 0.5),
    }
}

impl World {
    /// The same world scaled by `factor` about the origin (a map "1 % too wide" is 1.01).
    pub fn scaled(&self, factor: f64) -> World {
        let f = |p: (f64, f64)| (p.0 * factor, p.1 * factor);
        World {
            segments: self
                .segments
                .iter()
                .map(|s| Segment {
                    a: f(s.a),
                    b: f(s.b),
                })
                .collect(),
            bounds: (
                self.bounds.0 * factor,
                self.bounds.1 * factor,
                self.bounds.2 * factor,
                self.bounds.3 * factor,
            ),
        }
    }

    /// Exact distance from `(x, y)` along direction `angle` to the first wall, or `max_range`.
    pub fn ray_cast(&self, x: f64, y: f64, angle: f64, max_range: f64) -> f64 {
        let (dx, dy) = (angle.cos(), angle.sin());
        let mut best = max_range;
        for s in &self.segments {
            let (ex, ey) = (s.b.0 - s.a.0, s.b.1 - s.a.1);
            let den = dx * ey - dy * ex;
            if den.abs() < 1e-15 {
                continue;
            }
            let (wx, wy) = (s.a.0 - x, s.a.1 - y);
            let t = (wx * ey - wy * ex) / den; // along the ray
            let u = (wx * dy - wy * dx) / den; // along the segment
            if t > 1e-9 && (0.0..=1.0).contains(&u) && t < best {
                best = t;
            }
        }
        best
    }

    /// Rasterizes the walls into a `width × height` occupancy grid of `res`-metre cells whose
    /// cell (0, 0) has its lower-left corner at the bounds' minimum; row-major, row 0 = lowest y.
    /// A cell is occupied when a wall passes through it (sampled every res/8 along each wall).
    pub fn rasterize(&self, res: f64) -> (usize, usize, Vec<bool>) {
        let (x0, y0, x1, y1) = self.bounds;
        let w = ((x1 - x0) / res).ceil() as usize;
        let h = ((y1 - y0) / res).ceil() as usize;
        let mut occ = vec![false; w * h];
        for s in &self.segments {
            let len = ((s.b.0 - s.a.0).powi(2) + (s.b.1 - s.a.1).powi(2)).sqrt();
            let n = (len / (res / 8.0)).ceil().max(1.0) as usize;
            for i in 0..=n {
                let t = i as f64 / n as f64;
                let (px, py) = (s.a.0 + t * (s.b.0 - s.a.0), s.a.1 + t * (s.b.1 - s.a.1));
                let cx = ((px - x0) / res).floor();
                let cy = ((py - y0) / res).floor();
                if cx >= 0.0 && cy >= 0.0 && (cx as usize) < w && (cy as usize) < h {
                    occ[cy as usize * w + cx as usize] = true;
                }
            }
        }
        (w, h, occ)
    }
}

/// A small deterministic generator (SplitMix64) for reproducible synthetic scans.
pub use crate::splitmix::SplitMix64 as SplitMix;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ray_cast_hits_the_side_walls_and_the_end() {
        let w = corridor();
        // From the middle of the corridor, straight up at x = 0.5 (no door there): the wall at y = 2.
        assert!((w.ray_cast(0.5, 1.0, std::f64::consts::FRAC_PI_2, 30.0) - 1.0).abs() < 1e-12);
        // Straight ahead: the end wall at x = 12.
        assert!((w.ray_cast(4.0, 1.0, 0.0, 30.0) - 8.0).abs() < 1e-12);
        // Down into the first door on the lower side (1.3..2.2): the recess at y = −0.3.
        assert!((w.ray_cast(1.75, 1.0, -std::f64::consts::FRAC_PI_2, 30.0) - 1.3).abs() < 1e-12);
    }

    #[test]
    fn rasterization_marks_walls_only() {
        let (w, h, occ) = corridor().rasterize(0.05);
        let n = occ.iter().filter(|&&o| o).count();
        assert!(n > 400 && n < w * h / 4, "{n} of {}", w * h);
        // The corridor centre line is free.
        let row = ((1.0 + 0.5) / 0.05) as usize;
        assert!((20..240).all(|c| !occ[row * w + c]));
    }
}
