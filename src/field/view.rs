//! [`FieldView`]: a validated, zero-copy view of a distance-field blob (in flash or anywhere).

use super::blob::{parse_blob, BlobError, FieldHeader, CODE_MAX, ENCODING_U8_LINEAR};
#[cfg(feature = "tiled-field")]
use super::tiled::{TiledCells, ENCODING_TILED};

/// Where a view's codes live: one byte per cell (encoding 1) or deduplicated tiles
/// (encoding 2). Both are validated at parse; the per-cell read is O(1) in each.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Cells<'a> {
    /// Encoding 1: `width · height` codes, row-major.
    Raw(&'a [u8]),
    /// Encoding 2: a tile index and a tile pool (feature `tiled-field`).
    #[cfg(feature = "tiled-field")]
    Tiled(TiledCells<'a>),
}

/// A parsed distance-field blob: validated once, then every lookup is infallible.
///
/// It borrows the blob's bytes (any alignment, e.g. an `include_bytes!` in flash) and copies
/// nothing. Reading a cell is an index computation and one byte load (encoding 1), or two
/// loads through the tile index (encoding 2, tiled); [`FieldView::encoding`] says which.
///
/// # Coordinates
/// Map frame, metres. Cell `(ix, iy)` covers `[origin_x + ix·s, origin_x + (ix+1)·s) ×
/// [origin_y + iy·s, origin_y + (iy+1)·s)` with `s` the cell size; `iy = 0` is the lowest row.
/// A point off the map reads the cell nearest to it plus the Euclidean distance from the point
/// to the map's rectangle (docs/models.md#field), so an off-map endpoint looks unlikely rather than
/// uninformative.
#[derive(Clone, Copy, Debug)]
pub struct FieldView<'a> {
    header: FieldHeader,
    cells: Cells<'a>,
    /// Encoding 1's codes, empty for a tiled blob: the hot paths read this slice and take the
    /// out-of-line `code_slow` on a miss (only with `tiled-field`; without it a miss is `None`), so
    /// encoding 1 pays nothing for encoding 2.
    raw: &'a [u8],
    width_f: f32,
    height_f: f32,
    last_ix: u32,
    last_iy: u32,
    stride: usize,
    inv_cell_size: f32,
    step_m: f32,
    /// Code steps per cell length: `cell_size / step`.
    steps_per_cell: f32,
    /// A tiled blob's clamp code (0: none).
    #[cfg(feature = "tiled-field")]
    clamp_code: u8,
}

impl<'a> FieldView<'a> {
    /// Parses and checks a whole blob: every header field, both checksums, exact length.
    ///
    /// # Errors
    /// Any [`BlobError`] of the format, including [`BlobError::TrailingBytes`] when `bytes` is
    /// longer than the blob. Never panics, whatever the bytes.
    pub fn parse(bytes: &'a [u8]) -> Result<Self, BlobError> {
        let (view, rest) = Self::parse_prefix(bytes)?;
        if rest.is_empty() {
            Ok(view)
        } else {
            Err(BlobError::TrailingBytes)
        }
    }

    /// As [`FieldView::parse`], for a blob at the start of a longer region (a flash partition
    /// padded with erased bytes): returns the view and the bytes after the blob.
    ///
    /// # Errors
    /// As [`FieldView::parse`], without [`BlobError::TrailingBytes`].
    pub fn parse_prefix(bytes: &'a [u8]) -> Result<(Self, &'a [u8]), BlobError> {
        let parsed = parse_blob(bytes)?;
        let (header, encoding, payload, rest) = (
            parsed.header,
            parsed.encoding,
            parsed.payload,
            parsed.trailing,
        );
        #[cfg(feature = "tiled-field")]
        let clamp_code = parsed.clamp_code;
        #[cfg(feature = "tiled-field")]
        let cells = if encoding == ENCODING_TILED {
            Cells::Tiled(TiledCells::parse(&header, payload, clamp_code)?)
        } else {
            Cells::Raw(payload)
        };
        // Without the feature `parse_blob` accepts encoding 1 only.
        #[cfg(not(feature = "tiled-field"))]
        let cells = {
            let _ = encoding;
            Cells::Raw(payload)
        };
        let stride = usize::try_from(header.width).map_err(|_| BlobError::TooLarge)?;
        let step_m = header.step_m();
        let view = Self {
            header,
            cells,
            raw: match cells {
                Cells::Raw(c) => c,
                #[cfg(feature = "tiled-field")]
                Cells::Tiled(_) => &[],
            },
            width_f: header.width as f32,
            height_f: header.height as f32,
            last_ix: header.width.saturating_sub(1),
            last_iy: header.height.saturating_sub(1),
            stride,
            inv_cell_size: 1.0 / header.cell_size_m,
            step_m,
            steps_per_cell: header.cell_size_m / step_m,
            #[cfg(feature = "tiled-field")]
            clamp_code,
        };
        Ok((view, rest))
    }

    /// The blob's header.
    pub fn header(&self) -> &FieldHeader {
        &self.header
    }

    /// Width, cells.
    pub fn width(&self) -> u32 {
        self.header.width
    }

    /// Height, cells.
    pub fn height(&self) -> u32 {
        self.header.height
    }

    /// Cell size, metres.
    pub fn cell_size_m(&self) -> f32 {
        self.header.cell_size_m
    }

    /// `d_max`, metres: distances are clamped here (code 255).
    pub fn max_dist_m(&self) -> f32 {
        self.header.max_dist_m
    }

    /// One code step, metres (`d_max / 255`); the quantization error of a stored distance is at
    /// most half of it.
    pub fn step_m(&self) -> f32 {
        self.step_m
    }

    /// The clamp code of a tiled blob built with a clamp distance (`beamfield field build
    /// --clamp-m`): codes never exceed it, and a cell whose code equals it is **at least**
    /// [`FieldView::clamp_m`] from the nearest occupied cell (its true distance may be anything
    /// up to `d_max` or beyond). `None` without a clamp (every distance below `d_max` exact to
    /// the code).
    pub fn clamp_code(&self) -> Option<u8> {
        #[cfg(feature = "tiled-field")]
        let code = self.clamp_code;
        // Only a tiled blob has a clamp.
        #[cfg(not(feature = "tiled-field"))]
        let code = 0;
        (code != 0).then_some(code)
    }

    /// The clamp distance, metres (`clamp code · step`): distances at or beyond it are stored
    /// as it, so [`FieldView::distance_m`] reads `≥ clamp_m` as `clamp_m`. `None` without a
    /// clamp.
    pub fn clamp_m(&self) -> Option<f32> {
        self.clamp_code().map(|c| f32::from(c) * self.step_m)
    }

    /// The payload of an encoding-1 blob: one code per cell, row-major, row 0 = lowest y.
    /// **Empty for a tiled blob** (encoding 2), which stores no such array: read cells with
    /// [`FieldView::code`] (either encoding) or use [`FieldView::raw_codes`].
    pub fn codes(&self) -> &'a [u8] {
        self.raw_codes().unwrap_or(&[])
    }

    /// The one-byte-per-cell payload when the blob has encoding 1, `None` for a tiled blob.
    pub fn raw_codes(&self) -> Option<&'a [u8]> {
        match self.cells {
            Cells::Raw(c) => Some(c),
            #[cfg(feature = "tiled-field")]
            Cells::Tiled(_) => None,
        }
    }

    /// The blob's distance encoding: [`ENCODING_U8_LINEAR`] (1) or
    /// [`tiled::ENCODING_TILED`](super::tiled::ENCODING_TILED) (2, read only with the `tiled-field`
    /// feature). Both give the same codes.
    pub fn encoding(&self) -> u8 {
        match self.cells {
            Cells::Raw(_) => ENCODING_U8_LINEAR,
            #[cfg(feature = "tiled-field")]
            Cells::Tiled(_) => ENCODING_TILED,
        }
    }

    /// Tiles in the pool of a tiled blob (`None` for encoding 1).
    pub fn pool_tiles(&self) -> Option<usize> {
        match self.cells {
            Cells::Raw(_) => None,
            #[cfg(feature = "tiled-field")]
            Cells::Tiled(t) => Some(t.pool_tiles()),
        }
    }

    /// Where the codes live (for the per-encoding hot loops).
    pub(crate) fn cells(&self) -> Cells<'a> {
        self.cells
    }

    /// `width · height`.
    pub(crate) fn cell_count(&self) -> usize {
        self.stride * (self.last_iy as usize + 1)
    }

    /// The code of cell `(ix, iy)`, or `None` off the grid.
    pub fn code(&self, ix: u32, iy: u32) -> Option<u8> {
        if ix > self.last_ix || iy > self.last_iy {
            return None;
        }
        self.code_on_map(ix, iy)
    }

    /// The code of cell `(ix, iy)` known to be on the map (`None` never happens for such a
    /// cell of a validated view; a broken precondition gives `None`, not a wrong read).
    #[inline(always)]
    pub(crate) fn code_on_map(&self, ix: u32, iy: u32) -> Option<u8> {
        let i = (iy as usize)
            .wrapping_mul(self.stride)
            .wrapping_add(ix as usize);
        match self.raw.get(i) {
            Some(&c) => Some(c),
            // Without the tiled reader a miss has no other place to look: no call in the hot
            // loops (a call there, even a cold one, costs the per-pose path registers and about
            // 3 instructions per beam, docs/firmware.md).
            #[cfg(not(feature = "tiled-field"))]
            None => None,
            #[cfg(feature = "tiled-field")]
            None => self.code_slow(ix, iy),
        }
    }

    /// [`FieldView::code_on_map`] past encoding 1's slice: a tiled blob's cell (or `None`).
    /// Out of line, so the raw read stays the hot paths' only code.
    #[cfg(feature = "tiled-field")]
    #[inline(never)]
    #[cold]
    fn code_slow(&self, ix: u32, iy: u32) -> Option<u8> {
        match self.cells {
            Cells::Raw(_) => None,
            Cells::Tiled(t) => t.code(ix, iy),
        }
    }

    /// The code at row-major index `i = iy·width + ix` (`None` past the last cell). O(1) in
    /// both encodings (a division for a tiled blob). Only with `tiled-field`: without it the
    /// ray caster reads the raw slice alone.
    #[cfg(feature = "tiled-field")]
    #[inline(always)]
    pub(crate) fn code_at_index(&self, i: usize) -> Option<u8> {
        match self.cells {
            Cells::Raw(codes) => codes.get(i).copied(),
            #[cfg(feature = "tiled-field")]
            Cells::Tiled(t) => {
                // Out-of-bounds `i` of a raw blob never reaches here (see the raw arm).
                let iy = i.checked_div(self.stride)?;
                if iy > self.last_iy as usize {
                    return None;
                }
                t.code((i - iy * self.stride) as u32, iy as u32)
            }
        }
    }

    /// Map-frame metres to continuous grid coordinates (cell units, `0` at the origin).
    #[inline]
    pub fn to_grid(&self, x_m: f32, y_m: f32) -> (f32, f32) {
        (
            (x_m - self.header.origin_x_m) * self.inv_cell_size,
            (y_m - self.header.origin_y_m) * self.inv_cell_size,
        )
    }

    /// The code of the cell nearest to grid point `(gx, gy)` and the squared distance, in cell
    /// units, from the point to the map's rectangle (0 on the map).
    ///
    /// Branch-free and total: NaN coordinates read cell 0 (and give a NaN distance).
    #[inline(always)]
    pub(crate) fn lookup_grid(&self, gx: f32, gy: f32) -> (u8, f32) {
        // `max`/`min` return the non-NaN operand, and `as u32` saturates: no UB, no panic.
        let cx = gx.max(0.0).min(self.width_f);
        let cy = gy.max(0.0).min(self.height_f);
        let ex = gx - cx;
        let ey = gy - cy;
        let ix = (cx as u32).min(self.last_ix);
        let iy = (cy as u32).min(self.last_iy);
        let code = self.code_on_map(ix, iy).unwrap_or(CODE_MAX);
        (code, ex * ex + ey * ey)
    }

    /// The quantized distance index (0..=255) used by the likelihood table at grid point
    /// `(gx, gy)`: the cell's code on the map; off it, the nearest cell's code plus the off-map
    /// distance in code steps (rounded), clamped at 255.
    ///
    /// The on-map case is the fast path: two float-to-int conversions (saturating, so total),
    /// four compares, one multiply-add and one byte load. The off-map case (a predictable
    /// branch: endpoints off the map are rare) takes [`FieldView::off_map_index`].
    #[inline(always)]
    pub(crate) fn table_index(&self, gx: f32, gy: f32) -> u8 {
        let ix = gx as i32;
        let iy = gy as i32;
        // `as i32` truncates toward zero, so (−1, 0) also gives 0: the sign tests exclude it.
        let on = (gx >= 0.0)
            & (gy >= 0.0)
            & ((ix as u32) < self.header.width)
            & ((iy as u32) < self.header.height);
        if on {
            self.code_on_map(ix as u32, iy as u32).unwrap_or(CODE_MAX)
        } else {
            self.off_map_index(gx, gy)
        }
    }

    /// [`FieldView::table_index`] for a point off the map (or NaN: gives 255).
    #[inline(never)]
    fn off_map_index(&self, gx: f32, gy: f32) -> u8 {
        let (code, off2) = self.lookup_grid(gx, gy);
        let extra = (crate::math::sqrt(off2) * self.steps_per_cell + 0.5).min(255.0);
        u8::try_from(u32::from(code) + extra as u32).unwrap_or(CODE_MAX)
    }

    /// Distance from a map-frame point to the nearest occupied cell, metres, as stored:
    /// the cell's code times [`FieldView::step_m`], plus the exact Euclidean distance from the
    /// point to the map's rectangle when it lies off the map.
    ///
    /// Inside the map the result is at most `d_max`, or at most [`FieldView::clamp_m`] for a
    /// blob with a clamp, where that value means "this far or farther". Every finite point gives a finite result,
    /// however far off the map (1e18 m, `±f32::MAX`): the off-map part is computed in metres
    /// on halved coordinates with a scaled hypotenuse, so no intermediate square or difference
    /// overflows, and a distance beyond `f32::MAX` (possible only for points near `±f32::MAX`
    /// with the map far on the other side) saturates at `f32::MAX`. An infinite coordinate
    /// gives `f32::MAX`; a NaN coordinate gives NaN (there is no point to measure from).
    pub fn distance_m(&self, x_m: f32, y_m: f32) -> f32 {
        if x_m.is_nan() || y_m.is_nan() {
            return f32::NAN;
        }
        let (gx, gy) = self.to_grid(x_m, y_m);
        // The nearest cell's code: `lookup_grid` clamps the (possibly infinite) grid point.
        let (code, _) = self.lookup_grid(gx, gy);
        let h = &self.header;
        // Half the offset from the point to the map's rectangle along each axis: halving
        // before subtracting keeps every difference of two finite f32s finite (and is exact
        // down to subnormals).
        let half_off = |p: f32, lo: f32, cells: u32| {
            let hi = lo + cells as f32 * h.cell_size_m;
            let nearest = p.max(lo).min(hi);
            (0.5 * p - 0.5 * nearest).abs()
        };
        let hx = half_off(x_m, h.origin_x_m, h.width);
        let hy = half_off(y_m, h.origin_y_m, h.height);
        let (big, small) = (hx.max(hy), hx.min(hy));
        let half = if big == 0.0 {
            0.0
        } else if big == f32::INFINITY {
            f32::INFINITY
        } else {
            let r = small / big;
            big * crate::math::sqrt(1.0 + r * r)
        };
        (f32::from(code) * self.step_m + 2.0 * half).min(f32::MAX)
    }

    /// `1 / cell_size`, cells per metre.
    pub(crate) fn inv_cell_size(&self) -> f32 {
        self.inv_cell_size
    }
}

#[cfg(test)]
mod tests {
    use super::super::blob::emit_blob;
    use super::*;

    fn blob() -> Vec<u8> {
        // 3 × 2 cells of 0.5 m at origin (1, 2); codes = 10·(index).
        let h = FieldHeader::new(3, 2, 0.5, 1.0, 2.0);
        let codes: Vec<u8> = (0..6).map(|i| 10 * i).collect();
        let mut out = vec![0; h.required_len().unwrap()];
        emit_blob(&h, &codes, &mut out).unwrap();
        out
    }

    #[test]
    fn lookups_table() {
        let b = blob();
        let v = FieldView::parse(&b).unwrap();
        let step = 2.0f32 / 255.0;
        // (x, y, expected distance): cell-local points, then off-map points.
        let cases: [(f32, f32, f32); 6] = [
            (1.1, 2.1, 0.0),
            (1.6, 2.1, 10.0 * step),
            (2.4, 2.9, 50.0 * step),
            (2.4, 2.4, 20.0 * step),
            (0.0, 2.1, 1.0),
            (2.5 + 3.0, 3.0 + 4.0, 50.0 * step + 5.0),
        ];
        for (x, y, want) in cases {
            let got = v.distance_m(x, y);
            assert!((got - want).abs() < 1e-5, "({x}, {y}): {got} vs {want}");
        }
        assert_eq!(v.code(2, 1), Some(50));
        assert_eq!(v.code(3, 0), None);
        assert!(v.distance_m(f32::NAN, 0.0).is_nan());
    }

    #[test]
    fn trailing_policy() {
        let mut b = blob();
        b.push(0xFF);
        assert_eq!(FieldView::parse(&b).err(), Some(BlobError::TrailingBytes));
        let (v, rest) = FieldView::parse_prefix(&b).unwrap();
        assert_eq!((v.width(), rest), (3, &[0xFF][..]));
    }

    /// Without the `tiled-field` feature a tiled blob is a typed error, not a misread.
    #[cfg(not(feature = "tiled-field"))]
    #[test]
    fn tiled_blob_needs_the_feature() {
        use super::super::tiled::{emit_blob_tiled, tiled_max_len, tiled_scratch_len};
        let h = FieldHeader::new(3, 2, 0.5, 1.0, 2.0);
        let codes = [0, 1, 2, 253, 254, 255];
        let mut scratch = vec![0u32; tiled_scratch_len(&h).unwrap()];
        let mut out = vec![0u8; tiled_max_len(&h).unwrap()];
        let n = emit_blob_tiled(&h, &codes, &mut scratch, &mut out).unwrap();
        assert_eq!(
            FieldView::parse(&out[..n]).err(),
            Some(BlobError::UnsupportedEncoding(2))
        );
    }
}
