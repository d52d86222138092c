//! SIMD sphere leaves: a leaf's spheres copied into blocks of `B` lanes (SoA), padded with lanes that never hit.

use crate::geometry::Sphere;

/// Id of a padding lane.
pub const PAD: u32 = u32::MAX;

/// `B` spheres as rows of lanes: centers and squared radii (what [`Sphere::intersect`] reads) and the spheres'
/// ids in the scene. Padding lanes have NaN centers and radii, so every comparison in the ray-sphere test fails
/// and they never hit, and id [`PAD`].
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub struct Block<const B: usize> {
    /// Center x.
    pub cx: [f32; B],
    /// Center y.
    pub cy: [f32; B],
    /// Center z.
    pub cz: [f32; B],
    /// Squared radius, `radius * radius` as [`Sphere::intersect`] computes it.
    pub r2: [f32; B],
    /// Scene index of each lane's sphere, [`PAD`] for padding.
    pub ids: [u32; B],
}

const _: () = assert!(std::mem::size_of::<Block<8>>() == 160 && std::mem::size_of::<Block<16>>() == 320);

impl<const B: usize> Block<B> {
    /// A block of padding only.
    pub const PADDING: Self =
        Self { cx: [f32::NAN; B], cy: [f32::NAN; B], cz: [f32::NAN; B], r2: [f32::NAN; B], ids: [PAD; B] };

    /// The block of (at most `B`) `spheres`, whose scene indices are `ids`, padded.
    #[inline(always)]
    fn of(spheres: &[Sphere], ids: &[u32]) -> Self {
        let mut block = Self::PADDING;
        for (lane, (s, &id)) in spheres.iter().zip(ids).enumerate() {
            block.cx[lane] = s.center.x;
            block.cy[lane] = s.center.y;
            block.cz[lane] = s.center.z;
            block.r2[lane] = s.radius * s.radius;
            block.ids[lane] = id;
        }
        block
    }

    /// Appends blocks holding `spheres` (whose scene indices are `ids`), the last one padded; returns how many.
    pub fn append(out: &mut Vec<Self>, spheres: &[Sphere], ids: &[u32]) -> usize {
        assert_eq!(spheres.len(), ids.len());
        for (spheres, ids) in spheres.chunks(B).zip(ids.chunks(B)) {
            out.push(Self::of(spheres, ids));
        }
        ids.len().div_ceil(B)
    }

    /// [`Block::append`] into the first blocks of `out`, which must have room; returns how many.
    pub fn write(out: &mut [Self], spheres: &[Sphere], ids: &[u32]) -> usize {
        assert_eq!(spheres.len(), ids.len());
        for (block, (spheres, ids)) in out[..ids.len().div_ceil(B)].iter_mut().zip(spheres.chunks(B).zip(ids.chunks(B)))
        {
            *block = Self::of(spheres, ids);
        }
        ids.len().div_ceil(B)
    }

    /// Real (non-padding) lanes: they come first.
    #[inline(always)]
    pub fn len(&self) -> usize {
        self.ids.iter().take_while(|&&id| id != PAD).count()
    }

    /// True for a block of padding only (never built).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    #[test]
    fn blocks_are_filled_in_order_and_padded() {
        let spheres: Vec<Sphere> = (0..11).map(|i| Sphere::new(Vec3::splat(i as f32), 0.5 + i as f32)).collect();
        let ids: Vec<u32> = (0..11).rev().collect();
        let ordered: Vec<Sphere> = ids.iter().map(|&i| spheres[i as usize]).collect();
        let mut blocks = Vec::new();
        assert_eq!(Block::<4>::append(&mut blocks, &ordered, &ids), 3);
        assert_eq!(blocks.iter().map(Block::len).collect::<Vec<_>>(), [4, 4, 3]);
        assert_eq!(blocks[0].ids, [10, 9, 8, 7]);
        assert_eq!((blocks[2].cx[2], blocks[2].r2[2]), (0.0, 0.25));
        assert!(blocks[2].cx[3].is_nan() && blocks[2].ids[3] == PAD);
        let mut written = [Block::<4>::PADDING; 4];
        assert_eq!(Block::write(&mut written, &ordered, &ids), 3);
        assert_eq!(format!("{:?}", &written[..3]), format!("{blocks:?}"), "the blocks of append (NaN padding)");
        assert!(written[3].is_empty());
    }
}
