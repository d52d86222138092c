//! The primitives the wide BVH stores ([`WidePrimitive`]) and their blocks' leaf tests ([`LeafBlock`]): [`Sphere`]
//! in [`SphereBlock`], [`MollerTrumboreTriangle`] in [`MollerTrumboreBlock`], [`WatertightTriangle`] in
//! [`WatertightBlock`]; the SIMD tests are those of [`super::kernel::lanes`].

use glam::Vec3;

#[cfg(target_arch = "x86_64")]
use super::kernel::{lanes, vector::Vf};
use super::leaf::{LeafBlock, MollerTrumboreBlock, PAD, SphereBlock, WatertightBlock, WidePrimitive};
use super::ray::{RayLanes, Shear};
use crate::geometry::{MollerTrumboreTriangle, Sphere, Triangle, WatertightTriangle};

impl WidePrimitive for Sphere {
    type Block<const B: usize> = SphereBlock<B>;
}

impl<const B: usize> LeafBlock<B> for SphereBlock<B> {
    type Prim = Sphere;
    const PADDING: Self =
        Self { cx: [f32::NAN; B], cy: [f32::NAN; B], cz: [f32::NAN; B], r2: [f32::NAN; B], ids: [PAD; B] };

    #[inline(always)]
    fn ids(&self) -> &[u32; B] {
        &self.ids
    }

    #[inline(always)]
    fn set(&mut self, lane: usize, s: &Sphere, id: u32) {
        (self.cx[lane], self.cy[lane], self.cz[lane]) = (s.center.x, s.center.y, s.center.z);
        self.r2[lane] = s.radius * s.radius;
        self.ids[lane] = id;
    }

    /// [`Sphere::intersect`] with the squared radius stored. Padding lanes (NaN) never hit.
    #[inline(always)]
    fn lane(&self, r: &RayLanes, t_max: f32, lane: usize) -> f32 {
        let c = Vec3::new(self.cx[lane], self.cy[lane], self.cz[lane]);
        let r2 = self.r2[lane];
        let d = Vec3::from_array(r.dir);
        let f = Vec3::from_array(r.origin) - c;
        let a = r.a;
        let b = f.dot(d);
        let offset = f - d * (b / a);
        let disc = a * (r2 - offset.dot(offset));
        if disc < 0.0 {
            return f32::INFINITY;
        }
        let c = f.dot(f) - r2;
        let q = -(b + disc.sqrt().copysign(b));
        let (r0, r1) = (c / q, q / a);
        let (near, far) = if r0 <= r1 { (r0, r1) } else { (r1, r0) };
        if near > r.t_min && near < t_max {
            near
        } else if far > r.t_min && far < t_max {
            far
        } else {
            f32::INFINITY
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn lanes<V: Vf>(&self, first: usize, r: &RayLanes, t_max: f32) -> (V, V::M) {
        // SAFETY: forwarded from the caller.
        unsafe { lanes::spheres::<V, B>(self, first, r, t_max) }
    }

    fn floats(&self) -> impl Iterator<Item = f32> + '_ {
        [&self.cx, &self.cy, &self.cz, &self.r2].into_iter().flatten().copied()
    }
}

impl WidePrimitive for MollerTrumboreTriangle {
    type Block<const B: usize> = MollerTrumboreBlock<B>;
}

impl<const B: usize> LeafBlock<B> for MollerTrumboreBlock<B> {
    type Prim = MollerTrumboreTriangle;
    const PADDING: Self = Self { rows: [[[f32::NAN; B]; 3]; 4], ids: [PAD; B] };

    #[inline(always)]
    fn ids(&self) -> &[u32; B] {
        &self.ids
    }

    #[inline(always)]
    fn set(&mut self, lane: usize, t: &MollerTrumboreTriangle, id: u32) {
        let [p0, e1, e2, n] = t.0.moller_trumbore_frame();
        for (row, v) in self.rows.iter_mut().zip([p0, e1, e2, n]) {
            (row[0][lane], row[1][lane], row[2][lane]) = (v.x, v.y, v.z);
        }
        self.ids[lane] = id;
    }

    #[inline(always)]
    fn lane(&self, r: &RayLanes, t_max: f32, lane: usize) -> f32 {
        let [p0, e1, e2, n] = self.rows.map(|row| Vec3::new(row[0][lane], row[1][lane], row[2][lane]));
        Triangle::moller_trumbore(p0, e1, e2, n, &r.ray(), t_max).map_or(f32::INFINITY, |h| h.t)
    }

    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn lanes<V: Vf>(&self, first: usize, r: &RayLanes, t_max: f32) -> (V, V::M) {
        // SAFETY: forwarded from the caller.
        unsafe { lanes::moller_trumbore::<V, B>(self, first, r, t_max) }
    }

    fn floats(&self) -> impl Iterator<Item = f32> + '_ {
        self.rows.iter().flatten().flatten().copied()
    }
}

impl WidePrimitive for WatertightTriangle {
    type Block<const B: usize> = WatertightBlock<B>;

    /// The ray space's permutation and shear ([`Shear`]), which the SIMD leaf test would otherwise redo per block.
    #[inline(always)]
    fn prepare(ray: &mut RayLanes) {
        ray.shear = Shear::new(Vec3::from_array(ray.dir));
    }
}

impl<const B: usize> LeafBlock<B> for WatertightBlock<B> {
    type Prim = WatertightTriangle;
    const PADDING: Self = Self { rows: [[[f32::NAN; B]; 3]; 3], ids: [PAD; B] };

    #[inline(always)]
    fn ids(&self) -> &[u32; B] {
        &self.ids
    }

    #[inline(always)]
    fn set(&mut self, lane: usize, t: &WatertightTriangle, id: u32) {
        for (row, v) in self.rows.iter_mut().zip(t.0.p) {
            (row[0][lane], row[1][lane], row[2][lane]) = (v.x, v.y, v.z);
        }
        self.ids[lane] = id;
    }

    #[inline(always)]
    fn lane(&self, r: &RayLanes, t_max: f32, lane: usize) -> f32 {
        self.triangle(lane).intersect_watertight(&r.ray(), t_max).map_or(f32::INFINITY, |h| h.t)
    }

    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn lanes<V: Vf>(&self, first: usize, r: &RayLanes, t_max: f32) -> (V, V::M) {
        // SAFETY: forwarded from the caller.
        unsafe { lanes::watertight::<V, B>(self, first, r, t_max) }
    }

    fn floats(&self) -> impl Iterator<Item = f32> + '_ {
        self.rows.iter().flatten().flatten().copied()
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
        assert_eq!(SphereBlock::<4>::append(&mut blocks, &ordered, &ids), 3);
        assert_eq!(blocks.iter().map(SphereBlock::len).collect::<Vec<_>>(), [4, 4, 3]);
        assert_eq!(blocks[0].ids, [10, 9, 8, 7]);
        assert_eq!((blocks[2].cx[2], blocks[2].r2[2]), (0.0, 0.25));
        assert!(blocks[2].cx[3].is_nan() && blocks[2].ids[3] == PAD);
        let mut written = [SphereBlock::<4>::PADDING; 4];
        assert_eq!(SphereBlock::write(&mut written, &ordered, &ids), 3);
        assert_eq!(format!("{:?}", &written[..3]), format!("{blocks:?}"), "the blocks of append (NaN padding)");
        assert!(written[3].is_empty());
    }
}
