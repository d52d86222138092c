//! The box and sphere tests written once over a vector of f32 lanes ([`Vf`]: 4, 8 or 16 lanes).
//!
//! Every operation is the IEEE operation the scalar code does, in the same order (the vector's operations are
//! those of [`super::vector`]).

use super::vector::Vf;
use crate::accel::wide::leaf::{LeafBlock, MollerTrumboreBlock, SphereBlock, WatertightBlock};
use crate::accel::wide::node::WideNode;
use crate::accel::wide::ray::{FrustumLanes, RayLanes};
use crate::geometry::RayBoxTester;

/// [`super::Ops::boxes`] for `W = V::LANES` children.
///
/// # Safety
/// The CPU supports `V`'s instructions.
#[inline(always)]
pub unsafe fn boxes<V: Vf, const W: usize>(node: &WideNode<W>, r: &RayLanes, t_max: f32, dist: &mut [f32; W]) -> u32 {
    debug_assert_eq!(V::LANES, W);
    unsafe {
        let slab = |axis: usize| {
            let row = r.near_rows[axis];
            let (o, inv) = (V::splat(r.origin[axis]), V::splat(r.inv[axis]));
            let near = V::load(node.bounds.as_ptr().add(row).cast()).sub(o).mul(inv);
            let far = V::load(node.bounds.as_ptr().add(row ^ 1).cast()).sub(o).mul(inv);
            (near, far)
        };
        let ((x0, x1), (y0, y1), (z0, z1)) = (slab(0), slab(1), slab(2));
        let near = x0.hi(y0).hi(z0.hi(V::splat(r.t_min)));
        let far = x1.lo(y1).lo(z1).mul(V::splat(RayBoxTester::FAR_SCALE));
        near.store(dist.as_mut_ptr());
        V::bits(V::and(near.le(far), near.le(V::splat(t_max))))
    }
}

/// The frustum test of [`super::Ops::frustum_boxes`], `V::LANES == W` children at once.
///
/// # Safety
/// The CPU supports `V`'s instructions.
#[inline(always)]
pub unsafe fn frustum_boxes<V: Vf, const W: usize>(
    node: &WideNode<W>,
    f: &FrustumLanes,
    t_max: f32,
    dist: &mut [f32; W],
) -> u32 {
    debug_assert_eq!(V::LANES, W);
    unsafe {
        let row = |row: usize| V::load(node.bounds.as_ptr().add(row).cast());
        let (mut near, mut far) = (V::splat(f.t_min), V::splat(f32::INFINITY));
        for axis in 0..3 {
            if !f.used[axis] {
                continue;
            }
            let (lo, hi) = (V::splat(f.inv_lo[axis]), V::splat(f.inv_hi[axis]));
            let x = row(f.near_rows[axis]).sub(V::splat(f.origin_near[axis]));
            let y = row(f.near_rows[axis] ^ 1).sub(V::splat(f.origin_far[axis]));
            near = near.hi(x.mul(lo).lo(x.mul(hi)));
            far = far.lo(y.mul(lo).hi(y.mul(hi)));
        }
        let occupied = row(0).le(row(1));
        let far = far.mul(V::splat(RayBoxTester::FAR_SCALE));
        near.store(dist.as_mut_ptr());
        V::bits(V::and(occupied, V::and(near.le(far), near.le(V::splat(t_max)))))
    }
}

/// Distances (infinity where missed) and hit mask of `V::LANES` spheres from lane `first` of `block`.
///
/// # Safety
/// The CPU supports `V`'s instructions, and `first + V::LANES <= B`.
#[inline(always)]
pub unsafe fn spheres<V: Vf, const B: usize>(
    block: &SphereBlock<B>,
    first: usize,
    r: &RayLanes,
    t_max: f32,
) -> (V, V::M) {
    unsafe {
        let row = |lanes: &[f32; B]| V::load(lanes.as_ptr().add(first));
        let (cx, cy, cz, r2) = (row(&block.cx), row(&block.cy), row(&block.cz), row(&block.r2));
        let (dx, dy, dz) = (V::splat(r.dir[0]), V::splat(r.dir[1]), V::splat(r.dir[2]));
        let (fx, fy, fz) =
            (V::splat(r.origin[0]).sub(cx), V::splat(r.origin[1]).sub(cy), V::splat(r.origin[2]).sub(cz));
        let a = V::splat(r.a);
        let b = fx.mul(dx).add(fy.mul(dy)).add(fz.mul(dz));
        let s = b.div(a);
        let (px, py, pz) = (fx.sub(dx.mul(s)), fy.sub(dy.mul(s)), fz.sub(dz.mul(s)));
        let disc = a.mul(r2.sub(px.mul(px).add(py.mul(py)).add(pz.mul(pz))));
        // disc < 0 (or NaN, in padding lanes): sqrt gives NaN, so every comparison below fails.
        let c = fx.mul(fx).add(fy.mul(fy)).add(fz.mul(fz)).sub(r2);
        let q = b.add(disc.sqrt().copysign(b)).neg();
        let (r0, r1) = (c.div(q), q.div(a));
        let ordered = r0.le(r1);
        let (near, far) = (V::select(ordered, r0, r1), V::select(ordered, r1, r0));
        let (t_min, t_max) = (V::splat(r.t_min), V::splat(t_max));
        let near_ok = V::and(near.gt(t_min), near.lt(t_max));
        let far_ok = V::and(far.gt(t_min), far.lt(t_max));
        let t = V::select(near_ok, near, V::select(far_ok, far, V::splat(f32::INFINITY)));
        (t, V::or(near_ok, far_ok))
    }
}

/// Row `axis` of a triangle block's vector `rows`, lanes `first..first + V::LANES`.
#[inline(always)]
unsafe fn row<V: Vf, const B: usize>(rows: &[[f32; B]; 3], axis: usize, first: usize) -> V {
    // SAFETY: the caller's bound on `first`.
    unsafe { V::load(rows[axis].as_ptr().add(first)) }
}

/// Distances and hit mask of `V::LANES` triangles from lane `first`:
/// [`crate::geometry::Triangle::moller_trumbore`], operation for operation (`dot` and `cross` as glam's `Vec3`).
///
/// # Safety
/// The CPU supports `V`'s instructions, and `first + V::LANES <= B`.
#[inline(always)]
pub unsafe fn moller_trumbore<V: Vf, const B: usize>(
    block: &MollerTrumboreBlock<B>,
    first: usize,
    r: &RayLanes,
    t_max: f32,
) -> (V, V::M) {
    unsafe {
        let [p0, e1, e2, n] = &block.rows;
        let (dx, dy, dz) = (V::splat(r.dir[0]), V::splat(r.dir[1]), V::splat(r.dir[2]));
        let (nx, ny, nz) = (row::<V, B>(n, 0, first), row::<V, B>(n, 1, first), row::<V, B>(n, 2, first));
        let (zero, one) = (V::splat(0.0), V::splat(1.0));
        let det = dx.mul(nx).add(dy.mul(ny)).add(dz.mul(nz)).neg();
        // Padding lanes (NaN) fail here and in every comparison after.
        let nonzero = V::or(det.lt(zero), det.gt(zero));
        let inv_det = one.div(det);
        let sx = V::splat(r.origin[0]).sub(row::<V, B>(p0, 0, first));
        let sy = V::splat(r.origin[1]).sub(row::<V, B>(p0, 1, first));
        let sz = V::splat(r.origin[2]).sub(row::<V, B>(p0, 2, first));
        let rx = dy.mul(sz).sub(sy.mul(dz));
        let ry = dz.mul(sx).sub(sz.mul(dx));
        let rz = dx.mul(sy).sub(sx.mul(dy));
        let (ax, ay, az) = (row::<V, B>(e2, 0, first), row::<V, B>(e2, 1, first), row::<V, B>(e2, 2, first));
        let u = rx.mul(ax).add(ry.mul(ay)).add(rz.mul(az)).neg().mul(inv_det);
        let u_ok = V::and(zero.le(u), u.le(one));
        let (bx, by, bz) = (row::<V, B>(e1, 0, first), row::<V, B>(e1, 1, first), row::<V, B>(e1, 2, first));
        let v = rx.mul(bx).add(ry.mul(by)).add(rz.mul(bz)).mul(inv_det);
        let v_ok = V::and(zero.le(v), u.add(v).le(one));
        let t = sx.mul(nx).add(sy.mul(ny)).add(sz.mul(nz)).mul(inv_det);
        let t_ok = V::and(t.gt(V::splat(r.t_min)), t.lt(V::splat(t_max)));
        let hit = V::and(V::and(nonzero, u_ok), V::and(v_ok, t_ok));
        (V::select(hit, t, V::splat(f32::INFINITY)), hit)
    }
}

/// Distances and hit mask of `V::LANES` triangles from lane `first`:
/// [`crate::geometry::Triangle::intersect_watertight`], operation for operation; a lane whose edge function rounds
/// to exactly 0 takes the scalar test (which redoes the edge functions in f64). The ray space is `r.shear`, which
/// [`crate::accel::wide::leaf::WidePrimitive::prepare`] computed by the scalar test's operations.
///
/// # Safety
/// The CPU supports `V`'s instructions, and `first + V::LANES <= B`; `r` was prepared for watertight leaves.
#[inline(always)]
pub unsafe fn watertight<V: Vf, const B: usize>(
    block: &WatertightBlock<B>,
    first: usize,
    r: &RayLanes,
    t_max: f32,
) -> (V, V::M) {
    unsafe {
        let [kx, ky, kz] = r.shear.axes;
        let (sx, sy, sz) = (V::splat(r.shear.s[0]), V::splat(r.shear.s[1]), V::splat(r.shear.s[2]));
        let (ox, oy, oz) = (V::splat(r.origin[kx]), V::splat(r.origin[ky]), V::splat(r.origin[kz]));
        let [p0, p1, p2] = &block.rows;
        // Each vertex relative to the origin on the permuted axes (`p − o`, then indexed), then sheared.
        let (a_x, a_y, az) = (
            row::<V, B>(p0, kx, first).sub(ox),
            row::<V, B>(p0, ky, first).sub(oy),
            row::<V, B>(p0, kz, first).sub(oz),
        );
        let (b_x, b_y, bz) = (
            row::<V, B>(p1, kx, first).sub(ox),
            row::<V, B>(p1, ky, first).sub(oy),
            row::<V, B>(p1, kz, first).sub(oz),
        );
        let (c_x, c_y, cz) = (
            row::<V, B>(p2, kx, first).sub(ox),
            row::<V, B>(p2, ky, first).sub(oy),
            row::<V, B>(p2, kz, first).sub(oz),
        );
        let (ax, ay) = (a_x.sub(sx.mul(az)), a_y.sub(sy.mul(az)));
        let (bx, by) = (b_x.sub(sx.mul(bz)), b_y.sub(sy.mul(bz)));
        let (cx, cy) = (c_x.sub(sx.mul(cz)), c_y.sub(sy.mul(cz)));
        // E(p, q) = q.x·p.y − q.y·p.x: U = E(b, c), V = E(c, a), W = E(a, b).
        let u = cx.mul(by).sub(cy.mul(bx));
        let v = ax.mul(cy).sub(ay.mul(cx));
        let w = bx.mul(ay).sub(by.mul(ax));
        let zero = V::splat(0.0);
        // All of one sign (for finite values, the scalar test's "not both signs"; a NaN lane fails either way).
        let nonneg = V::and(V::and(zero.le(u), zero.le(v)), zero.le(w));
        let nonpos = V::and(V::and(u.le(zero), v.le(zero)), w.le(zero));
        let det = u.add(v).add(w);
        let det_ok = V::or(det.lt(zero), det.gt(zero));
        let t_scaled = u.mul(sz.mul(az)).add(v.mul(sz.mul(bz))).add(w.mul(sz.mul(cz)));
        let t = t_scaled.mul(V::splat(1.0).div(det));
        let t_ok = V::and(t.gt(V::splat(r.t_min)), t.lt(V::splat(t_max)));
        let hit = V::and(V::and(V::or(nonneg, nonpos), det_ok), t_ok);
        let t = V::select(hit, t, V::splat(f32::INFINITY));
        let exact = V::bits(V::or(V::or(u.eq(zero), v.eq(zero)), w.eq(zero)));
        if exact == 0 {
            return (t, hit);
        }
        let mut ts = [f32::INFINITY; 16];
        t.store(ts.as_mut_ptr());
        let mut lane = 0;
        while lane < V::LANES {
            if exact >> lane & 1 == 1 {
                ts[lane] = LeafBlock::lane(block, r, t_max, first + lane);
            }
            lane += 1;
        }
        let t = V::load(ts.as_ptr());
        (t, t.lt(V::splat(f32::INFINITY)))
    }
}

/// [`super::Ops::closest`] in `B / V::LANES` vectors (at most 4).
///
/// # Safety
/// The CPU supports `V`'s instructions.
#[inline(always)]
pub unsafe fn closest<V: Vf, L: LeafBlock<B>, const B: usize>(
    block: &L,
    r: &RayLanes,
    t_max: f32,
) -> Option<(f32, usize)> {
    unsafe {
        let n = B / V::LANES;
        let mut ts = [V::splat(f32::INFINITY); 4];
        let mut hit = 0;
        for (k, t) in ts.iter_mut().enumerate().take(n) {
            let (tk, mk) = block.lanes::<V>(k * V::LANES, r, t_max);
            *t = tk;
            hit |= V::bits(mk) << (k * V::LANES);
        }
        if hit == 0 {
            return None;
        }
        let nearest = ts[..n].iter().fold(V::splat(f32::INFINITY), |m, &t| m.lo(t)).reduce_lo();
        let at = V::splat(nearest);
        let lanes = ts[..n].iter().enumerate().fold(0, |bits, (k, t)| bits | V::bits(t.eq(at)) << (k * V::LANES));
        Some((nearest, lanes.trailing_zeros() as usize))
    }
}

/// [`super::Ops::any`] in `B / V::LANES` vectors.
///
/// A plain loop, no iterator adapter: a closure is a function of its own, compiled without the kernel's target
/// features when not inlined, and then every intrinsic in it is a call (AVX2 shadow rays ran 3.5x slower than
/// scalar ones that way).
///
/// # Safety
/// The CPU supports `V`'s instructions.
#[inline(always)]
pub unsafe fn any<V: Vf, L: LeafBlock<B>, const B: usize>(block: &L, r: &RayLanes, t_max: f32) -> bool {
    unsafe {
        let mut k = 0;
        while k < B / V::LANES {
            if V::bits(block.lanes::<V>(k * V::LANES, r, t_max).1) != 0 {
                return true;
            }
            k += 1;
        }
        false
    }
}
