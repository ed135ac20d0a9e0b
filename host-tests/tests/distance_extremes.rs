//! `FieldView::distance_m` at extreme coordinates, against an f64 computation of its definition
//! (docs/blob-format.md): the nearest cell's stored distance (code × d_max/255) plus the
//! Euclidean distance from the point to the map's rectangle.
//!
//! Every finite point must give a finite distance (points 1e18 m off the map gave `inf` when the
//! off-map part was squared in grid units); a distance above `f32::MAX` saturates there, an
//! infinite coordinate gives `f32::MAX`, and NaN gives NaN.

use beamfield::field::{emit_blob, FieldHeader, FieldView};

const W: u32 = 4;
const H: u32 = 3;

fn blob(cell_m: f32, origin: (f32, f32)) -> Vec<u8> {
    let h = FieldHeader::new(W, H, cell_m, origin.0, origin.1);
    // Distinct codes, so the nearest cell is checked too.
    let codes: Vec<u8> = (0..W * H).map(|i| (7 + 20 * i) as u8).collect();
    let mut out = vec![0u8; h.required_len().unwrap()];
    emit_blob(&h, &codes, &mut out).unwrap();
    out
}

/// The definition in f64: nearest cell's code × step plus the distance to the rectangle.
fn expected(view: &FieldView<'_>, x: f64, y: f64) -> f64 {
    let h = view.header();
    let s = f64::from(h.cell_size_m);
    let (x0, y0) = (f64::from(h.origin_x_m), f64::from(h.origin_y_m));
    let (x1, y1) = (x0 + f64::from(W) * s, y0 + f64::from(H) * s);
    let cx = x.clamp(x0, x1);
    let cy = y.clamp(y0, y1);
    let ix = (((cx - x0) / s).floor() as u32).min(W - 1);
    let iy = (((cy - y0) / s).floor() as u32).min(H - 1);
    let code = 7 + 20 * (iy * W + ix);
    let step = f64::from(h.max_dist_m) / 255.0;
    f64::from(code) * step + ((x - cx).powi(2) + (y - cy).powi(2)).sqrt()
}

fn check(view: &FieldView<'_>, x: f32, y: f32) {
    let got = view.distance_m(x, y);
    let want = expected(view, f64::from(x), f64::from(y));
    assert!(got.is_finite(), "({x:e}, {y:e}): {got} (want {want:e})");
    if want > f64::from(f32::MAX) {
        assert_eq!(got, f32::MAX, "({x:e}, {y:e}): saturates (want {want:e})");
    } else {
        // A few f32 roundings of the result's magnitude (halving, subtraction, the scaled
        // hypotenuse's division, square root and products: ≤ 8 ulp), plus the code step's.
        let tol = 8.0 * f64::from(f32::EPSILON) * want.abs() + 1e-6;
        assert!(
            (f64::from(got) - want).abs() <= tol,
            "({x:e}, {y:e}): {got:e} vs {want:e}"
        );
    }
}

#[test]
fn far_points_give_finite_distances() {
    let b = blob(0.05, (-10.0, 5.0));
    let view = FieldView::parse(&b).unwrap();
    let m = f32::MAX;
    for (x, y) in [
        // On the map and just off it.
        (-9.99, 5.01),
        (-9.81, 5.14),
        (-10.5, 5.07),
        (-9.7, 4.0),
        // About 1e18 m off, on each side and diagonally (these gave inf).
        (1e18, 5.05),
        (-1e18, 5.05),
        (-9.9, 1e18),
        (-9.9, -1e18),
        (1e18, -1e18),
        (-1e18, 1e18),
        (3e19, 2e19),
        // At f32::MAX: along an axis it is finite; diagonally it saturates.
        (m, 5.05),
        (-m, 5.05),
        (-9.9, m),
        (-9.9, -m),
        (m, m),
        (-m, m),
        (m, -m),
        (-m, -m),
    ] {
        check(&view, x, y);
    }
}

/// A map far from the frame's origin: a point at `+f32::MAX` is more than `f32::MAX` away
/// (saturates), one at 1e18 m is about 3e38 m away (finite). The difference `x − x_map` itself
/// overflows f32 here, which the halving avoids.
#[test]
fn far_map_far_point() {
    let b = blob(1.0, (-3.0e38, 0.0));
    let view = FieldView::parse(&b).unwrap();
    for (x, y) in [
        (1e18, 1.0),
        (f32::MAX, 1.0),
        (-f32::MAX, 1.0),
        (1e18, 1e18),
        (0.0, -3.0e38),
    ] {
        check(&view, x, y);
    }
}

#[test]
fn infinite_and_nan_coordinates() {
    let b = blob(0.05, (-10.0, 5.0));
    let view = FieldView::parse(&b).unwrap();
    let inf = f32::INFINITY;
    for (x, y) in [(inf, 5.0), (-inf, 5.0), (-9.9, inf), (inf, -inf)] {
        assert_eq!(view.distance_m(x, y), f32::MAX, "({x}, {y})");
    }
    for (x, y) in [(f32::NAN, 5.0), (-9.9, f32::NAN), (f32::NAN, inf)] {
        assert!(view.distance_m(x, y).is_nan(), "({x}, {y})");
    }
}
