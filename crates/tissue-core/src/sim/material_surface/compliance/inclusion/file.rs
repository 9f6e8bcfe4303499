//! The inclusions' correction kept in a file that proves what it is, as the background's
//! compliance is ([`crate::sim::material_surface::compliance::file`]): a header with the format's
//! magic bytes and version and the crc32 checksum of everything after it, then the full key (the
//! method's version, the face divisions, the material's key: the background's `C`, each
//! inclusion's centre, radius and `C`), then the correction. A file whose format, length,
//! checksum or key does not match is refused, never used.
//!
//! The layout, little-endian:
//!
//! | bytes | holds |
//! |---|---|
//! | 0..8 | [`INCLUSION_MAGIC`] |
//! | 8..12 | [`INCLUSION_FORMAT`] (u32) |
//! | 12..16 | the crc32 of every byte from 16 to the end (u32) |
//! | 16..20 | [`INCLUSION_METHOD_VERSION`] (u32) |
//! | 20..24 | the face divisions per axis (u32) |
//! | 24..32 | how many f64 the key holds, `k` (u64) |
//! | 32.. | the key (`k` f64), the surface nodes' rows (`u64` count, then u32 each), the nodes held (u64), the blocks' values (`u64` count, then f32 each) |

use super::InclusionCorrection;
use crate::mechanics::material::Material;
use crate::sim::material_surface::compliance::file::FileError;

/// The first bytes of a correction file.
pub const INCLUSION_MAGIC: [u8; 8] = *b"TSIMLUMP";
/// The version of the file's layout.
pub const INCLUSION_FORMAT: u32 = 1;
/// The version of the computation (its mesh, reach and method): a change makes old files refused.
pub const INCLUSION_METHOD_VERSION: u32 = 1;

/// Reads the bytes of a file in order, each read checked to be there.
struct Cursor<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Cursor<'_> {
    fn take<const N: usize>(&mut self) -> Result<[u8; N], FileError> {
        let end = self.at.checked_add(N).filter(|&e| e <= self.bytes.len()).ok_or(FileError::Truncated)?;
        let out = std::array::from_fn(|i| self.bytes[self.at + i]);
        self.at = end;
        Ok(out)
    }
    fn u32(&mut self) -> Result<u32, FileError> {
        Ok(u32::from_le_bytes(self.take()?))
    }
    fn u64(&mut self) -> Result<u64, FileError> {
        Ok(u64::from_le_bytes(self.take()?))
    }
    /// A count of items of `size` bytes each that the remaining bytes can hold.
    fn count(&mut self, size: usize) -> Result<usize, FileError> {
        let n = self.u64()?;
        let left = (self.bytes.len() - self.at) as u64;
        if n.checked_mul(size as u64).is_none_or(|b| b > left) {
            return Err(FileError::Truncated);
        }
        Ok(n as usize)
    }
}

impl InclusionCorrection {
    /// The correction as the bytes of its file, keyed by `material` (with its inclusions) and
    /// the lattice's `divisions`.
    pub fn to_bytes(&self, material: &Material, divisions: usize) -> Vec<u8> {
        let key = material.key();
        let mut out = Vec::with_capacity(64 + 8 * key.len() + 4 * (self.rows.len() + self.values.len()));
        out.extend_from_slice(&INCLUSION_MAGIC);
        out.extend_from_slice(&INCLUSION_FORMAT.to_le_bytes());
        out.extend_from_slice(&[0; 4]);
        out.extend_from_slice(&INCLUSION_METHOD_VERSION.to_le_bytes());
        out.extend_from_slice(&(divisions as u32).to_le_bytes());
        out.extend_from_slice(&(key.len() as u64).to_le_bytes());
        key.iter().for_each(|k| out.extend_from_slice(&k.to_le_bytes()));
        out.extend_from_slice(&(self.rows.len() as u64).to_le_bytes());
        self.rows.iter().for_each(|r| out.extend_from_slice(&r.to_le_bytes()));
        out.extend_from_slice(&(self.count as u64).to_le_bytes());
        out.extend_from_slice(&(self.values.len() as u64).to_le_bytes());
        self.values.iter().for_each(|v| out.extend_from_slice(&v.to_le_bytes()));
        let crc = crc32fast::hash(&out[16..]);
        out[12..16].copy_from_slice(&crc.to_le_bytes());
        out
    }

    /// Reads [`InclusionCorrection::to_bytes`]: the correction of `material` on a lattice of
    /// `divisions` with `nodes` surface nodes, or why `bytes` are not it (checked in this order:
    /// the format, the checksum, the method, the key, the layout).
    pub fn from_bytes(bytes: &[u8], material: &Material, divisions: usize, nodes: usize) -> Result<Self, FileError> {
        if bytes.len() < 16 {
            let cut = bytes.starts_with(&INCLUSION_MAGIC) || INCLUSION_MAGIC.starts_with(bytes);
            return Err(if cut { FileError::Truncated } else { FileError::Format });
        }
        if bytes[..8] != INCLUSION_MAGIC || u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) != INCLUSION_FORMAT {
            return Err(FileError::Format);
        }
        if crc32fast::hash(&bytes[16..]) != u32::from_le_bytes([bytes[12], bytes[13], bytes[14], bytes[15]]) {
            return Err(FileError::Checksum);
        }
        let mut c = Cursor { bytes, at: 16 };
        if c.u32()? != INCLUSION_METHOD_VERSION {
            return Err(FileError::Method);
        }
        if c.u32()? as usize != divisions {
            return Err(FileError::Grid);
        }
        let key = material.key();
        let k = c.count(8)?;
        let mut same = k == key.len();
        for i in 0..k {
            let v = c.u64()?;
            same &= key.get(i).is_some_and(|x| x.to_bits() == v);
        }
        if !same {
            return Err(FileError::Material);
        }
        let rows: Vec<u32> = (0..c.count(4)?).map(|_| c.u32()).collect::<Result<_, _>>()?;
        let count = c.u64()? as usize;
        let values: Vec<f32> =
            (0..c.count(4)?).map(|_| c.take::<4>().map(f32::from_le_bytes)).collect::<Result<_, _>>()?;
        if c.at != bytes.len() {
            return Err(FileError::TooLong);
        }
        let held = rows.iter().filter(|&&r| r != u32::MAX).count();
        let fits = rows.len() == nodes
            && held == count
            && rows.iter().all(|&r| r == u32::MAX || (r as usize) < count)
            && count.checked_mul(count).and_then(|c| c.checked_mul(9)) == Some(values.len());
        if !fits {
            return Err(FileError::Inconsistent);
        }
        if values.iter().any(|v| !v.is_finite()) {
            return Err(FileError::NotFinite);
        }
        Ok(Self { rows, count, values })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::inclusion::Inclusion;

    fn with_inclusions() -> Material {
        let mut m = Material::object_a();
        m.inclusions.push(Inclusion { centre: [0.05, 0.05, 0.08], radius: 0.008, stiffness: m.stiffness * 5.0 });
        m
    }

    fn small() -> InclusionCorrection {
        InclusionCorrection {
            rows: vec![u32::MAX, 0, 1, u32::MAX],
            count: 2,
            values: (0..36).map(|v| v as f32 * 1e-6).collect(),
        }
    }

    #[test]
    fn the_file_round_trips_and_refuses_another_key_or_changed_bytes() {
        let (m, c) = (with_inclusions(), small());
        let bytes = c.to_bytes(&m, 10);
        assert_eq!(InclusionCorrection::from_bytes(&bytes, &m, 10, 4), Ok(c.clone()));
        let mut other = with_inclusions();
        other.inclusions[0].radius = 0.009;
        assert_eq!(InclusionCorrection::from_bytes(&bytes, &other, 10, 4), Err(FileError::Material));
        assert_eq!(InclusionCorrection::from_bytes(&bytes, &Material::object_a(), 10, 4), Err(FileError::Material));
        assert_eq!(InclusionCorrection::from_bytes(&bytes, &m, 12, 4), Err(FileError::Grid));
        assert_eq!(InclusionCorrection::from_bytes(&bytes, &m, 10, 5), Err(FileError::Inconsistent));
        let mut changed = bytes.clone();
        *changed.last_mut().expect("bytes") ^= 1;
        assert_eq!(InclusionCorrection::from_bytes(&changed, &m, 10, 4), Err(FileError::Checksum));
        assert_eq!(InclusionCorrection::from_bytes(&bytes[..bytes.len() - 3], &m, 10, 4), Err(FileError::Checksum));
        assert_eq!(InclusionCorrection::from_bytes(&bytes[..10], &m, 10, 4), Err(FileError::Truncated));
        assert_eq!(InclusionCorrection::from_bytes(b"surface-compliance", &m, 10, 4), Err(FileError::Format));
    }
}
