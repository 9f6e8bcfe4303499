//! The compact form of a surface compliance: what `assets/compliance/` ships for objects A and B,
//! so that their probe pushes back like the material from the first press, with nothing to
//! compute.
//!
//! A column of the compliance is smooth away from its own node (it falls off about as one over
//! the distance), so each entry is predicted from its neighbours on a coarser grid of the face
//! and only the prediction's error is kept, quantised: an interpolating wavelet. Per family and
//! column, every target has a level (how many times both its in-face lattice indices halve, at
//! most [`LEVELS`]); the targets of the top level are kept as they are, those of a level below it
//! are predicted as the mean of their two (or, odd along both axes, four diagonal) neighbours one
//! step of their level away on the same face, where all of those are targets of the column, and
//! kept as they are where not. Each entry is then `prediction + r * q` with an integer `r` and
//! the column's step `q` = [`STEP`] times its largest entry: no entry is off by more than `q / 2`
//! (the prediction is made from the entries as they will be read back, so the error does not
//! grow from level to level). Far from the column's node the `r` are mostly 0, which deflate
//! (flate2) packs to almost nothing; the varints of `r` are this file's own (no crate of the
//! build has them).
//!
//! The layout, little-endian (the header as [`super::file`]'s, then the deflated body):
//!
//! | bytes | holds |
//! |---|---|
//! | 0..8 | [`COMPACT_MAGIC`] |
//! | 8..12 | [`COMPACT_FORMAT`] (u32) |
//! | 12..16 | the crc32 of every byte from 16 to the end (u32) |
//! | 16..20 | [`super::METHOD_VERSION`] (u32) |
//! | 20..24 | the face divisions per axis (u32) |
//! | 24..312 | the material's stiffness `C` (Voigt, Pa), row by row (36 f64) |
//! | 312..320 | [`STEP`] it was written with (f64) |
//! | 320..328 | the body's length inflated (u64) |
//! | 328.. | the body, deflated: per family, per column, its step `q` (f64), then per force and displacement component (`3 b + a`), per target by level from the top, the zigzag varint of `r` |

use std::io::{Read, Write};

use super::file::{FileError, METHOD_VERSION, array, stiffness_rows, u32_at};
use super::lattice::{Family, Lattice};
use super::SurfaceCompliance;
use crate::mechanics::material::Material;

/// The first bytes of a compact surface compliance.
pub const COMPACT_MAGIC: [u8; 8] = *b"TSIMSCCZ";
/// The version of the compact layout.
pub const COMPACT_FORMAT: u32 = 1;
/// A column's quantisation step, relative to its largest entry (the self-compliance of its own
/// node): every entry read back is within half of it. Measured on object A's compliance (91
/// presses of 5 to 30 mm spheres, 1 mm to 3/4 of the radius deep, on the top face, a side, an
/// edge and a corner): 1e-4 gives 7.2 MB and forces within 0.021 % of the full compliance's, 3e-4
/// 4.5 MB and 0.063 %, 1e-3 2.6 MB and 0.16 %, 3e-3 1.6 MB and 0.52 %.
pub const STEP: f64 = 1e-3;
/// Levels of the prediction: a target whose in-face indices are multiples of `2^LEVELS` is kept
/// as it is.
pub const LEVELS: u32 = 4;
/// Bytes of the header in front of the deflated body.
const HEADER_BYTES: usize = 328;
/// Where the checksum is, and where the bytes it covers start.
const CHECKSUM_AT: usize = 12;
const CHECKED_FROM: usize = 16;

/// How a family's column is read: the targets in the order they are kept (the top level first)
/// and, per target, the neighbours its prediction is the mean of (none: kept as it is).
struct Plan {
    order: Vec<u32>,
    neighbours: Vec<([u32; 4], u8)>,
}

impl Plan {
    fn of(f: &Family, d: usize) -> Self {
        let level = |q: &[usize; 3]| -> u32 {
            (0..3)
                .filter(|&c| q[c] > 0 && q[c] < d)
                .map(|c| q[c].trailing_zeros())
                .min()
                .unwrap_or(LEVELS)
                .min(LEVELS)
        };
        let levels: Vec<u32> = f.targets.iter().map(level).collect();
        let neighbours = f
            .targets
            .iter()
            .zip(&levels)
            .map(|(q, &l)| {
                let mut out = ([0u32; 4], 0u8);
                if l >= LEVELS {
                    return out;
                }
                let step = 1usize << l;
                let odd: Vec<usize> =
                    (0..3).filter(|&c| q[c] > 0 && q[c] < d && q[c].trailing_zeros() == l).collect();
                for corner in 0..(1usize << odd.len()) {
                    let mut p = *q;
                    for (bit, &c) in odd.iter().enumerate() {
                        p[c] = if corner >> bit & 1 == 0 { q[c] - step } else { q[c] + step };
                    }
                    match (p.iter().all(|&c| c <= d)).then(|| f.target_at(p, d)).flatten() {
                        Some(t) => {
                            out.0[usize::from(out.1)] = t as u32;
                            out.1 += 1;
                        }
                        None => return ([0; 4], 0),
                    }
                }
                out
            })
            .collect();
        let mut order: Vec<u32> = (0..f.targets.len() as u32).collect();
        order.sort_by_key(|&t| std::cmp::Reverse(levels[t as usize]));
        Self { order, neighbours }
    }

    /// The prediction of target `t` from the entries read back so far.
    #[inline]
    fn predict(&self, t: usize, read: &[f64]) -> f64 {
        let (n, count) = &self.neighbours[t];
        if *count == 0 {
            return 0.0;
        }
        n[..usize::from(*count)].iter().map(|&s| read[s as usize]).sum::<f64>() / f64::from(*count)
    }
}

/// Whether `bytes` are a compact form keyed by `material`'s stiffness (their header only: the
/// body is checked when read).
pub fn is_for(bytes: &[u8], material: &Material) -> bool {
    bytes.len() >= HEADER_BYTES
        && stiffness_rows(material)
            .iter()
            .enumerate()
            .all(|(k, c)| u64::from_le_bytes(array(bytes, 24 + 8 * k)) == c.to_bits())
}

fn push_varint(out: &mut Vec<u8>, r: i64) {
    let mut z = ((r << 1) ^ (r >> 63)) as u64;
    while z >= 0x80 {
        out.push((z as u8) | 0x80);
        z >>= 7;
    }
    out.push(z as u8);
}

/// Reads the body: its bytes and where the next is.
struct Body<'b> {
    bytes: &'b [u8],
    at: usize,
}

impl Body<'_> {
    fn varint(&mut self) -> Result<i64, FileError> {
        let mut z = 0u64;
        for shift in (0..64).step_by(7) {
            let b = *self.bytes.get(self.at).ok_or(FileError::Truncated)?;
            self.at += 1;
            z |= u64::from(b & 0x7f) << shift;
            if b & 0x80 == 0 {
                return Ok((z >> 1) as i64 ^ -((z & 1) as i64));
            }
        }
        Err(FileError::Inconsistent)
    }

    fn f64(&mut self) -> Result<f64, FileError> {
        let b = self.bytes.get(self.at..self.at + 8).ok_or(FileError::Truncated)?;
        self.at += 8;
        Ok(f64::from_le_bytes(array(b, 0)))
    }
}

impl SurfaceCompliance {
    /// The compliance in its compact form, keyed by `material` (the material it was computed
    /// for): every entry within [`STEP`] / 2 of its column's largest.
    pub fn to_compact(&self, material: &Material) -> Vec<u8> {
        let d = self.lattice.last();
        let mut body = Vec::new();
        let mut read = Vec::new();
        for f in &self.lattice.families {
            let plan = Plan::of(f, d);
            let n = f.targets.len();
            for c in 0..f.columns() {
                let column = &self.columns[f.offset + 9 * n * c..f.offset + 9 * n * (c + 1)];
                let largest = column.iter().fold(0.0f64, |m, v| m.max(f64::from(v.abs())));
                let q = if largest > 0.0 { STEP * largest } else { 1.0 };
                body.extend_from_slice(&q.to_le_bytes());
                for k in 0..9 {
                    read.clear();
                    read.resize(n, 0.0);
                    for &t in &plan.order {
                        let t = t as usize;
                        let predicted = plan.predict(t, &read);
                        let r = ((f64::from(column[9 * t + k]) - predicted) / q).round() as i64;
                        read[t] = predicted + r as f64 * q;
                        push_varint(&mut body, r);
                    }
                }
            }
        }
        let mut out = Vec::with_capacity(HEADER_BYTES + body.len() / 8);
        out.extend_from_slice(&COMPACT_MAGIC);
        out.extend_from_slice(&COMPACT_FORMAT.to_le_bytes());
        out.extend_from_slice(&[0; 4]);
        out.extend_from_slice(&METHOD_VERSION.to_le_bytes());
        out.extend_from_slice(&(self.lattice.divisions as u32).to_le_bytes());
        for c in stiffness_rows(material) {
            out.extend_from_slice(&c.to_le_bytes());
        }
        out.extend_from_slice(&STEP.to_le_bytes());
        out.extend_from_slice(&(body.len() as u64).to_le_bytes());
        let mut deflate = flate2::write::DeflateEncoder::new(out, flate2::Compression::best());
        // Writing into memory does not fail.
        let _ = deflate.write_all(&body);
        let mut out = deflate.finish().unwrap_or_default();
        let crc = crc32fast::hash(&out[CHECKED_FROM..]);
        out[CHECKSUM_AT..CHECKED_FROM].copy_from_slice(&crc.to_le_bytes());
        out
    }

    /// The largest difference of an entry of `other` from this compliance's, relative to the
    /// largest entry of its column (1 where the two are not of one lattice).
    pub fn largest_difference(&self, other: &Self) -> f64 {
        if self.lattice != other.lattice {
            return 1.0;
        }
        let mut worst = 0.0f64;
        for f in &self.lattice.families {
            let n = 9 * f.targets.len();
            for c in 0..f.columns() {
                let span = f.offset + n * c..f.offset + n * (c + 1);
                let (a, b) = (&self.columns[span.clone()], &other.columns[span]);
                let largest = a.iter().fold(0.0f64, |m, v| m.max(f64::from(v.abs())));
                let diff = a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max(f64::from((x - y).abs())));
                worst = worst.max(if largest > 0.0 { diff / largest } else { diff });
            }
        }
        worst
    }

    /// Reads [`SurfaceCompliance::to_compact`]: the compliance of `material` with `divisions`
    /// face divisions per axis, or why `bytes` are not it (checked in this order: the format, the
    /// checksum, the key, the body).
    pub fn from_compact(bytes: &[u8], material: &Material, divisions: usize) -> Result<Self, FileError> {
        if bytes.len() < HEADER_BYTES {
            let cut = bytes.starts_with(&COMPACT_MAGIC) || COMPACT_MAGIC.starts_with(bytes);
            return Err(if cut { FileError::Truncated } else { FileError::Format });
        }
        if bytes[..8] != COMPACT_MAGIC || u32_at(bytes, 8) != COMPACT_FORMAT {
            return Err(FileError::Format);
        }
        if crc32fast::hash(&bytes[CHECKED_FROM..]) != u32_at(bytes, CHECKSUM_AT) {
            return Err(FileError::Checksum);
        }
        if u32_at(bytes, 16) != METHOD_VERSION {
            return Err(FileError::Method);
        }
        if u32_at(bytes, 20) as usize != divisions || !divisions.is_multiple_of(2) || divisions < 2 {
            return Err(FileError::Grid);
        }
        if !is_for(bytes, material) {
            return Err(FileError::Material);
        }
        let lattice = Lattice::new(divisions);
        let columns: usize = lattice.families.iter().map(Family::columns).sum();
        let length = u64::from_le_bytes(array(bytes, 320));
        // At least a byte a value and a step a column, at most ten bytes a value.
        let (least, most) = (lattice.values + 8 * columns, 10 * lattice.values + 8 * columns);
        if length < least as u64 || length > most as u64 {
            return Err(FileError::Inconsistent);
        }
        let mut body = Vec::with_capacity(length as usize);
        flate2::read::DeflateDecoder::new(&bytes[HEADER_BYTES..])
            .take(length + 1)
            .read_to_end(&mut body)
            .map_err(|_| FileError::Inconsistent)?;
        match body.len().cmp(&(length as usize)) {
            std::cmp::Ordering::Less => return Err(FileError::Truncated),
            std::cmp::Ordering::Greater => return Err(FileError::TooLong),
            std::cmp::Ordering::Equal => {}
        }
        let mut body = Body { bytes: &body, at: 0 };
        let mut values = vec![0.0f32; lattice.values];
        let d = lattice.last();
        let mut read = Vec::new();
        for f in &lattice.families {
            let plan = Plan::of(f, d);
            let n = f.targets.len();
            for c in 0..f.columns() {
                let q = body.f64()?;
                if !(q.is_finite() && q > 0.0) {
                    return Err(FileError::NotFinite);
                }
                let column = &mut values[f.offset + 9 * n * c..f.offset + 9 * n * (c + 1)];
                for k in 0..9 {
                    read.clear();
                    read.resize(n, 0.0);
                    for &t in &plan.order {
                        let t = t as usize;
                        let v = plan.predict(t, &read) + body.varint()? as f64 * q;
                        read[t] = v;
                        column[9 * t + k] = v as f32;
                    }
                }
            }
        }
        if body.at != body.bytes.len() {
            return Err(FileError::TooLong);
        }
        if values.iter().any(|v| !v.is_finite()) {
            return Err(FileError::NotFinite);
        }
        Ok(Self { lattice, columns: values.into(), correction: None })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A compliance of `divisions` with smooth made-up columns (one over the distance from the
    /// column's node, as a real one falls off).
    fn smooth(divisions: usize) -> SurfaceCompliance {
        let lattice = Lattice::new(divisions);
        let d = lattice.last();
        let mut columns = vec![0.0f32; lattice.values];
        for f in &lattice.families {
            let n = f.targets.len();
            for c in 0..f.columns() {
                let p = f.column_point(c, d).map(|i| lattice.coords[i]);
                for (t, q) in f.targets.iter().enumerate() {
                    let x = q.map(|i| lattice.coords[i]);
                    let r = (0..3).map(|a| (x[a] - p[a]).powi(2)).sum::<f64>().sqrt();
                    for k in 0..9 {
                        let v = 1e-3 / (1.0 + r / 0.002) * (1.0 + 0.1 * k as f64) * if k % 4 == 0 { 1.0 } else { -0.3 };
                        columns[f.offset + 9 * (n * c + t) + k] = v as f32;
                    }
                }
            }
        }
        SurfaceCompliance { lattice, columns: columns.into(), correction: None }
    }

    #[test]
    fn the_compact_form_reads_back_within_half_a_step_and_is_smaller() {
        let a = Material::object_a();
        let c = smooth(10);
        let bytes = c.to_compact(&a);
        let back = SurfaceCompliance::from_compact(&bytes, &a, 10).expect("read back");
        let largest = c.columns.iter().fold(0.0f32, |m, v| m.max(v.abs()));
        let worst = c.columns.iter().zip(back.columns.iter()).fold(0.0f32, |m, (x, y)| m.max((x - y).abs()));
        assert!(f64::from(worst) <= 0.5 * STEP * f64::from(largest) * 1.01, "{worst} of {largest}");
        assert!(bytes.len() < c.columns.len(), "{} bytes for {} values", bytes.len(), c.columns.len());
        assert_eq!(SurfaceCompliance::from_compact(&bytes, &Material::object_b(), 10), Err(FileError::Material));
        assert_eq!(SurfaceCompliance::from_compact(&bytes, &a, 12), Err(FileError::Grid));
        assert_eq!(SurfaceCompliance::from_compact(&c.to_bytes(&a), &a, 10), Err(FileError::Format));
    }

    #[test]
    fn every_prediction_is_made_from_targets_read_before_it() {
        let lattice = Lattice::new(50);
        for f in &lattice.families {
            let plan = Plan::of(f, lattice.last());
            let mut seen = vec![false; f.targets.len()];
            for &t in &plan.order {
                let (n, count) = plan.neighbours[t as usize];
                assert!(n[..usize::from(count)].iter().all(|&s| seen[s as usize]), "{:?}", f.targets[t as usize]);
                seen[t as usize] = true;
            }
        }
    }

    proptest::proptest! {
        /// Any one byte of a compact form changed (to any other value), or the form cut short, is
        /// refused: never read as another compliance.
        #[test]
        fn any_one_byte_corruption_or_cut_of_the_compact_form_is_refused(
            at in 0usize..1_000_000,
            flip in 1u8..=255,
        ) {
            let a = Material::object_a();
            let bytes = smooth(4).to_compact(&a);
            let mut bad = bytes.clone();
            let at = at % bad.len();
            bad[at] ^= flip;
            proptest::prop_assert!(SurfaceCompliance::from_compact(&bad, &a, 4).is_err(), "byte {} changed was read", at);
            proptest::prop_assert!(SurfaceCompliance::from_compact(&bytes[..at], &a, 4).is_err(), "cut at {} was read", at);
        }
    }
}
