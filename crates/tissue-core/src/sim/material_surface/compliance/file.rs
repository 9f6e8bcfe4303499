//! The surface compliance kept in a file that proves what it is: a header with the format's magic
//! bytes and version, the crc32 checksum of everything after it, and the full key (the method's
//! version, the face divisions, the material's stiffness `C`), then the f32 columns. A file whose
//! format, length, checksum or key does not match is refused ([`FileError`]), never used.
//!
//! The layout, little-endian:
//!
//! | bytes | holds |
//! |---|---|
//! | 0..8 | [`FILE_MAGIC`] |
//! | 8..12 | [`FILE_FORMAT`] (u32) |
//! | 12..16 | the crc32 of every byte from 16 to the end (u32) |
//! | 16..20 | [`METHOD_VERSION`] (u32) |
//! | 20..24 | the face divisions per axis (u32) |
//! | 24..312 | the material's stiffness `C` (Voigt, Pa), row by row (36 f64) |
//! | 312..320 | how many f32 values follow (u64) |
//! | 320.. | the columns (f32) |
//!
//! The density is not in the key: the compliance is static and depends on `C` alone.

use super::SurfaceCompliance;
use crate::mechanics::material::Material;

/// The first bytes of a surface compliance file.
pub const FILE_MAGIC: [u8; 8] = *b"TSIMSCMP";
/// The version of the file's layout (1 was the bare `divisions` header before the key and the
/// checksum).
pub const FILE_FORMAT: u32 = 2;
/// The version of the computation: a change of method makes old files refused (1 held the top
/// face only; 2 a uniform lattice, without the halved rows across the edges; 3 held a column's
/// three force components apart, not a target's 3 x 3 block together).
pub const METHOD_VERSION: u32 = 4;
/// Bytes of the header in front of the columns.
const HEADER_BYTES: usize = 320;
/// The checksum covers the bytes from here to the end (the key and the columns).
const CHECKED_FROM: usize = 16;
/// Where the checksum is.
const CHECKSUM_AT: usize = 12;
/// Where the stiffness starts.
const STIFFNESS_AT: usize = 24;
/// Where the count of columns' values is.
const COUNT_AT: usize = 312;

/// Why bytes are not the surface compliance asked for: each reads after "the file".
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum FileError {
    /// Not this format's magic bytes and version (another file, or an older version's).
    #[error("is not a surface compliance file of this version's format")]
    Format,
    /// Shorter than its header says.
    #[error("is truncated")]
    Truncated,
    /// Longer than its header says.
    #[error("is longer than its header says")]
    TooLong,
    /// The checksum does not match: bytes changed after it was written.
    #[error("is damaged (its checksum does not match)")]
    Checksum,
    /// Computed by another version of the method.
    #[error("was computed by another version of the method")]
    Method,
    /// For another number of face divisions.
    #[error("is for another face grid")]
    Grid,
    /// For another material's stiffness.
    #[error("is for another material")]
    Material,
    /// The header's count does not fit its divisions.
    #[error("has a header that does not fit its columns")]
    Inconsistent,
    /// A value is not finite.
    #[error("holds values that are not finite")]
    NotFinite,
}

/// The key's stiffness: `C` row by row.
pub(super) fn stiffness_rows(material: &Material) -> [f64; 36] {
    std::array::from_fn(|k| material.stiffness[(k / 6, k % 6)])
}

/// The `N` bytes at `at` (within the bytes checked to be there).
pub(super) fn array<const N: usize>(bytes: &[u8], at: usize) -> [u8; N] {
    std::array::from_fn(|i| bytes[at + i])
}

pub(super) fn u32_at(bytes: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(array(bytes, at))
}

/// The bytes of a file of this layout: `magic`, the key of `material` and `divisions`, the
/// count of `values`, then `extra` (a part file's family) and the values.
fn seal(magic: &[u8; 8], divisions: usize, material: &Material, extra: &[u8], values: &[f32]) -> Vec<u8> {
    let mut out = Vec::with_capacity(HEADER_BYTES + extra.len() + 4 * values.len());
    out.extend_from_slice(magic);
    out.extend_from_slice(&FILE_FORMAT.to_le_bytes());
    out.extend_from_slice(&[0; 4]);
    out.extend_from_slice(&METHOD_VERSION.to_le_bytes());
    out.extend_from_slice(&(divisions as u32).to_le_bytes());
    for c in stiffness_rows(material) {
        out.extend_from_slice(&c.to_le_bytes());
    }
    out.extend_from_slice(&(values.len() as u64).to_le_bytes());
    debug_assert_eq!(out.len(), HEADER_BYTES);
    out.extend_from_slice(extra);
    for v in values {
        out.extend_from_slice(&v.to_le_bytes());
    }
    let crc = crc32fast::hash(&out[CHECKED_FROM..]);
    out[CHECKSUM_AT..CHECKED_FROM].copy_from_slice(&crc.to_le_bytes());
    out
}

/// Reads [`seal`]'s bytes with `extra` bytes after the header: those bytes and the values, or why
/// they are not `material`'s for `divisions` (checked in this order: the format, the length, the
/// checksum, the key, finite values).
fn open<'b>(
    bytes: &'b [u8],
    magic: &[u8; 8],
    extra: usize,
    material: &Material,
    divisions: usize,
) -> Result<(&'b [u8], Vec<f32>), FileError> {
    let header = HEADER_BYTES + extra;
    if bytes.len() < header {
        let cut = bytes.starts_with(magic) || magic.starts_with(bytes);
        return Err(if cut { FileError::Truncated } else { FileError::Format });
    }
    if bytes[..magic.len()] != *magic || u32_at(bytes, 8) != FILE_FORMAT {
        return Err(FileError::Format);
    }
    let count = u64::from_le_bytes(array(bytes, COUNT_AT));
    let expected = u128::from(count) * 4 + header as u128;
    match (bytes.len() as u128).cmp(&expected) {
        std::cmp::Ordering::Less => return Err(FileError::Truncated),
        std::cmp::Ordering::Greater => return Err(FileError::TooLong),
        std::cmp::Ordering::Equal => {}
    }
    if crc32fast::hash(&bytes[CHECKED_FROM..]) != u32_at(bytes, CHECKSUM_AT) {
        return Err(FileError::Checksum);
    }
    if u32_at(bytes, 16) != METHOD_VERSION {
        return Err(FileError::Method);
    }
    if u32_at(bytes, 20) as usize != divisions {
        return Err(FileError::Grid);
    }
    let same = stiffness_rows(material)
        .iter()
        .enumerate()
        .all(|(k, c)| u64::from_le_bytes(array(bytes, STIFFNESS_AT + 8 * k)) == c.to_bits());
    if !same {
        return Err(FileError::Material);
    }
    if !divisions.is_multiple_of(2) || divisions < 2 {
        return Err(FileError::Inconsistent);
    }
    let values: Vec<f32> =
        bytes[header..].chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
    if values.iter().any(|v| !v.is_finite()) {
        return Err(FileError::NotFinite);
    }
    Ok((&bytes[HEADER_BYTES..header], values))
}

/// The first bytes of a part file: one family's columns, kept while the others are computed.
pub const PART_MAGIC: [u8; 8] = *b"TSIMSCPT";

/// Family `family`'s columns (`values`) of `material`'s compliance on `divisions` as the bytes of
/// a part file: the whole file's layout with [`PART_MAGIC`] and the family's index (u32) after the
/// header.
pub fn part_to_bytes(material: &Material, divisions: usize, family: usize, values: &[f32]) -> Vec<u8> {
    seal(&PART_MAGIC, divisions, material, &(family as u32).to_le_bytes(), values)
}

/// Reads [`part_to_bytes`]: family `family`'s columns of `material`'s compliance on `divisions`,
/// `len` values, or why `bytes` are not them.
pub fn part_from_bytes(
    bytes: &[u8],
    material: &Material,
    divisions: usize,
    family: usize,
    len: usize,
) -> Result<Vec<f32>, FileError> {
    let (extra, values) = open(bytes, &PART_MAGIC, 4, material, divisions)?;
    if u32_at(extra, 0) as usize != family || values.len() != len {
        return Err(FileError::Inconsistent);
    }
    Ok(values)
}

impl SurfaceCompliance {
    /// The compliance as the bytes of its file ([`crate::sim::material_surface::compliance::file`]'s
    /// layout), keyed by `material`, the material it was computed for.
    pub fn to_bytes(&self, material: &Material) -> Vec<u8> {
        seal(&FILE_MAGIC, self.lattice.divisions, material, &[], &self.columns)
    }

    /// Reads [`SurfaceCompliance::to_bytes`]: the compliance of `material` with `divisions` face
    /// divisions per axis, or why `bytes` are not it (checked in this order: the format, the
    /// length, the checksum, the key).
    pub fn from_bytes(bytes: &[u8], material: &Material, divisions: usize) -> Result<Self, FileError> {
        let (_, columns) = open(bytes, &FILE_MAGIC, 0, material, divisions)?;
        let lattice = super::lattice::Lattice::new(divisions);
        if columns.len() != lattice.values {
            return Err(FileError::Inconsistent);
        }
        Ok(Self { lattice, columns: columns.into(), correction: None })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A compliance of two divisions with made-up values (the file does not care).
    fn small() -> SurfaceCompliance {
        let lattice = super::super::lattice::Lattice::new(2);
        let columns = (0..lattice.values).map(|i| 1e-6 * i as f32).collect::<Vec<f32>>().into();
        SurfaceCompliance { lattice, columns, correction: None }
    }

    /// `bytes` with the checksum made to match again (a file written so).
    fn resealed(mut bytes: Vec<u8>) -> Vec<u8> {
        let crc = crc32fast::hash(&bytes[CHECKED_FROM..]);
        bytes[CHECKSUM_AT..CHECKED_FROM].copy_from_slice(&crc.to_le_bytes());
        bytes
    }

    #[test]
    fn the_file_round_trips_with_its_key() {
        let (a, c) = (Material::object_a(), small());
        let bytes = c.to_bytes(&a);
        assert_eq!(bytes.len(), HEADER_BYTES + 4 * c.columns.len());
        assert_eq!(bytes[..8], FILE_MAGIC);
        assert_eq!(SurfaceCompliance::from_bytes(&bytes, &a, 2), Ok(c));
    }

    #[test]
    fn another_key_is_refused() {
        let (a, c) = (Material::object_a(), small());
        let bytes = c.to_bytes(&a);
        assert_eq!(SurfaceCompliance::from_bytes(&bytes, &Material::object_b(), 2), Err(FileError::Material));
        assert_eq!(SurfaceCompliance::from_bytes(&bytes, &a, 4), Err(FileError::Grid));
        let mut other = bytes.clone();
        other[16..20].copy_from_slice(&(METHOD_VERSION + 1).to_le_bytes());
        assert_eq!(SurfaceCompliance::from_bytes(&resealed(other), &a, 2), Err(FileError::Method));
        let mut nan = bytes;
        let at = nan.len() - 4;
        nan[at..].copy_from_slice(&f32::NAN.to_le_bytes());
        assert_eq!(SurfaceCompliance::from_bytes(&resealed(nan), &a, 2), Err(FileError::NotFinite));
    }

    #[test]
    fn changed_bytes_are_refused_by_the_checksum() {
        let (a, c) = (Material::object_a(), small());
        let bytes = c.to_bytes(&a);
        // Zeros in the middle of the body, one bit of the body, one bit of the key.
        let mut zeroed = bytes.clone();
        let mid = zeroed.len() / 2;
        zeroed[mid - 100..mid + 100].fill(0);
        for at in [HEADER_BYTES + 40, STIFFNESS_AT + 3] {
            let mut flipped = bytes.clone();
            flipped[at] ^= 1;
            assert_eq!(SurfaceCompliance::from_bytes(&flipped, &a, 2), Err(FileError::Checksum), "byte {at}");
        }
        assert_eq!(SurfaceCompliance::from_bytes(&zeroed, &a, 2), Err(FileError::Checksum));
    }

    #[test]
    fn a_cut_longer_or_foreign_file_is_refused() {
        let (a, c) = (Material::object_a(), small());
        let bytes = c.to_bytes(&a);
        for cut in [0, 5, 100, HEADER_BYTES, bytes.len() - 1] {
            assert_eq!(SurfaceCompliance::from_bytes(&bytes[..cut], &a, 2), Err(FileError::Truncated), "{cut}");
        }
        let mut longer = bytes.clone();
        longer.push(0);
        assert_eq!(SurfaceCompliance::from_bytes(&longer, &a, 2), Err(FileError::TooLong));
        // The earlier format: the divisions as a u64, then the columns.
        let mut old = 2u64.to_le_bytes().to_vec();
        old.extend(c.columns.iter().flat_map(|v| v.to_le_bytes()));
        assert_eq!(SurfaceCompliance::from_bytes(&old, &a, 2), Err(FileError::Format));
        let mut format = bytes;
        format[8] = 3;
        assert_eq!(SurfaceCompliance::from_bytes(&format, &a, 2), Err(FileError::Format));
    }

    proptest::proptest! {
        /// Any compliance read back from its file is itself, and any one byte changed (to any
        /// other value) is refused: never read as another compliance.
        #[test]
        fn a_kept_file_round_trips_and_any_one_byte_corruption_is_refused(
            values in proptest::collection::vec(-1e-3f32..1e-3, 1..4),
            at in 0usize..100_000,
            flip in 1u8..=255,
        ) {
            let a = Material::object_a();
            let lattice = super::super::lattice::Lattice::new(2);
            let columns =
                (0..lattice.values).map(|i| values[i % values.len()] * (1.0 + i as f32)).collect::<Vec<f32>>().into();
            let c = SurfaceCompliance { lattice, columns, correction: None };
            let bytes = c.to_bytes(&a);
            proptest::prop_assert_eq!(SurfaceCompliance::from_bytes(&bytes, &a, 2), Ok(c));
            let mut bad = bytes;
            let at = at % bad.len();
            bad[at] ^= flip;
            proptest::prop_assert!(SurfaceCompliance::from_bytes(&bad, &a, 2).is_err(), "byte {} changed was read", at);
        }
    }
}
