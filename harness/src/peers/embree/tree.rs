//! Embree's own builder (`rtcBuildBVH`, the `GeneralBVHBuilder` core its scene builders share) over a triangle
//! mesh, its tree copied out as a binary tree of [`FlatNode`]s that our tracer collapses and traces
//! (`tree_builder = "embree"` / `"embree-high"`; docs/embree-trees.md says where it differs from the tree
//! `rtcCommitScene` builds).

use std::ffi::{c_uint, c_void};

use glam::Vec3A;
use tracer::accel::bvh::split::Box3A;
use tracer::accel::bvh::split::clip::{box_halves, is_empty, triangle_halves};
use tracer::accel::bvh::tree::{FlatNode, MAX_DEPTH};
use tracer::geometry::Aabb;
use tracer::scene::mesh::Mesh;

use super::abi::*;
use super::device::{EmbreeDevice, EmbreeError};

/// Which of Embree's builders makes the tree.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TreeQuality {
    /// Binned SAH (`RTC_BUILD_QUALITY_MEDIUM`), what `rtcCommitScene` runs for a scene of default quality.
    Medium,
    /// Binned SAH with spatial splits through our `splitPrimitive` (`RTC_BUILD_QUALITY_HIGH`), 20% spare references
    /// as Embree's internal triangle builder has (`max_spatial_split_replications` 1.2).
    High,
}

/// The settings of Embree's internal BVH8 triangle builders (`BVHNBuilderSAH<8, Triangle4>`, read in
/// `kernels/bvh/bvh_builder_sah.cpp`): SAH cost in blocks of 4 triangles, a node of at most 4 always a leaf, leaves
/// up to 28 triangles (7 blocks) where the SAH says so, unit costs. The tree is binary (our collapse makes it
/// 8-wide) and at most `MAX_DEPTH` deep, leaving Embree's 8 levels for large leaves.
const SAH_BLOCK: u32 = 4;
const MIN_LEAF: u32 = 4;
const MAX_LEAF: u32 = 28;
/// Spare references for spatial splits, as a fraction of the triangle count.
const SPATIAL_SPARE: f64 = 0.2;

/// Widest node the callbacks accept (Embree's `MAX_BRANCHING_FACTOR` is 16; we ask for 2).
const MAX_CHILDREN: usize = 8;
const INNER: u32 = 0x4e4e_4921;
const LEAF: u32 = 0x4641_454c;

/// An inner node as our callbacks write it, in memory the BVH owns.
#[repr(C)]
struct Inner {
    tag: u32,
    count: u32,
    children: [*mut c_void; MAX_CHILDREN],
    bounds: [Aabb; MAX_CHILDREN],
}

/// A leaf: `count` primitive ids follow the header in the same allocation.
#[repr(C)]
struct Leaf {
    tag: u32,
    count: u32,
}

/// What the callbacks read: the mesh (for `splitPrimitive`) and the allocator of the BVH.
struct Context<'a> {
    mesh: &'a Mesh,
    alloc: FnThreadLocalAlloc,
}

/// Embree's tree over `mesh`: binary nodes (left child at `first`, right at `first + 1`) and the triangle ids
/// its leaves name, a triangle named in several leaves where a spatial split cut it.
pub fn build(
    device: &EmbreeDevice,
    mesh: &Mesh,
    quality: TreeQuality,
) -> Result<(Vec<FlatNode>, Vec<u32>), EmbreeError> {
    let n = mesh.triangle_count();
    if n == 0 {
        return Err(EmbreeError::Input("a mesh without triangles".into()));
    }
    if n > u32::MAX as usize / 2 {
        return Err(EmbreeError::Input(format!("{n} triangles: more than Embree's builder takes")));
    }
    let capacity = match quality {
        TreeQuality::Medium => n,
        TreeQuality::High => n + (n as f64 * SPATIAL_SPARE).ceil() as usize,
    };
    // The array Embree reorders (and, for spatial splits, fills up to its capacity): 32-byte aligned by the type.
    let mut prims = vec![RTCBuildPrimitive::default(); capacity];
    let mut root_box = Aabb::EMPTY;
    for (i, (p, t)) in prims.iter_mut().zip(mesh.triangles()).enumerate() {
        let b = t.bounds();
        root_box = root_box.union(&b);
        *p = RTCBuildPrimitive {
            lower_x: b.min.x,
            lower_y: b.min.y,
            lower_z: b.min.z,
            geomID: 0,
            upper_x: b.max.x,
            upper_y: b.max.y,
            upper_z: b.max.z,
            primID: i as u32,
        };
    }
    assert_eq!((prims.as_ptr() as usize) % align_of::<RTCBuildPrimitive>(), 0, "Embree reads primitives aligned");
    let inner = &device.inner;
    let api = inner.lib.api;
    let context = Context { mesh, alloc: api.thread_local_alloc };
    let _measuring = inner.measuring();
    inner.take_error();
    // SAFETY: a live device.
    let bvh = unsafe { (api.new_bvh)(inner.raw) };
    if bvh.is_null() {
        return Err(EmbreeError::Api(inner.take_error().unwrap_or_else(|| "rtcNewBVH returned null".into())));
    }
    let args = RTCBuildArguments {
        byteSize: size_of::<RTCBuildArguments>(),
        buildQuality: match quality {
            TreeQuality::Medium => RTC_BUILD_QUALITY_MEDIUM,
            TreeQuality::High => RTC_BUILD_QUALITY_HIGH,
        },
        buildFlags: 0,
        maxBranchingFactor: 2,
        maxDepth: (MAX_DEPTH - 8) as c_uint,
        sahBlockSize: SAH_BLOCK,
        minLeafSize: MIN_LEAF,
        maxLeafSize: MAX_LEAF,
        traversalCost: 1.0,
        intersectionCost: 1.0,
        bvh,
        primitives: prims.as_mut_ptr(),
        primitiveCount: n,
        primitiveArrayCapacity: capacity,
        createNode: Some(create_node),
        setNodeChildren: Some(set_node_children),
        setNodeBounds: Some(set_node_bounds),
        createLeaf: Some(create_leaf),
        splitPrimitive: match quality {
            TreeQuality::Medium => None,
            TreeQuality::High => Some(split_triangle),
        },
        buildProgress: None,
        userPtr: &context as *const Context as *mut c_void,
    };
    // SAFETY: the arguments point at `prims` (capacity entries, aligned) and `context`, both alive until the build
    // returns; the callbacks below keep to the nodes they are handed.
    let root = unsafe { (api.build_bvh)(&args) };
    let result = if root.is_null() {
        Err(EmbreeError::Api(inner.take_error().unwrap_or_else(|| "rtcBuildBVH returned null".into())))
    } else {
        // SAFETY: `root` and everything below it were written by the callbacks, in memory the BVH still owns.
        unsafe { copy_out(root, root_box, n) }.map_err(EmbreeError::Api)
    };
    // SAFETY: `bvh` came from rtcNewBVH; nothing refers to its memory after the copy.
    unsafe { (api.release_bvh)(bvh) };
    result
}

/// Allocates `bytes` from the BVH's thread-local allocator, 16-byte aligned.
///
/// # Safety
/// `alloc` is the allocator Embree passed to the calling callback; `user` is the build's [`Context`].
unsafe fn allocate(alloc: RTCThreadLocalAllocator, bytes: usize, user: *mut c_void) -> *mut c_void {
    // SAFETY: the caller's contract.
    let context = unsafe { &*(user as *const Context) };
    // SAFETY: as above; Embree aborts the build itself where it cannot allocate.
    let p = unsafe { (context.alloc)(alloc, bytes, 16) };
    assert!(!p.is_null() && (p as usize).is_multiple_of(16), "rtcThreadLocalAlloc gave no 16-byte aligned memory");
    p
}

unsafe extern "C" fn create_node(
    alloc: RTCThreadLocalAllocator,
    child_count: c_uint,
    user: *mut c_void,
) -> *mut c_void {
    // SAFETY: Embree's allocator and our context.
    let p = unsafe { allocate(alloc, size_of::<Inner>(), user) } as *mut Inner;
    let node = Inner {
        tag: INNER,
        count: child_count.min(MAX_CHILDREN as u32),
        children: [std::ptr::null_mut(); MAX_CHILDREN],
        bounds: [Aabb::EMPTY; MAX_CHILDREN],
    };
    // SAFETY: a fresh allocation of this size and alignment (Inner's is 8).
    unsafe { p.write(node) };
    p as *mut c_void
}

unsafe extern "C" fn set_node_children(
    node: *mut c_void,
    children: *mut *mut c_void,
    child_count: c_uint,
    _user: *mut c_void,
) {
    // SAFETY: `node` is one of ours; Embree passes `child_count` children, each touched by one thread only.
    let node = unsafe { &mut *(node as *mut Inner) };
    for i in 0..(child_count as usize).min(MAX_CHILDREN) {
        node.children[i] = unsafe { children.add(i).read_unaligned() };
    }
    node.count = child_count; // a count over MAX_CHILDREN is refused when the tree is copied out
}

unsafe extern "C" fn set_node_bounds(
    node: *mut c_void,
    bounds: *const *const RTCBounds,
    child_count: c_uint,
    _user: *mut c_void,
) {
    // SAFETY: as in `set_node_children`.
    let node = unsafe { &mut *(node as *mut Inner) };
    for i in 0..(child_count as usize).min(MAX_CHILDREN) {
        // Read without assuming Embree's 16-byte alignment of the box (nothing here relies on it).
        let b = unsafe { bounds.add(i).read_unaligned().read_unaligned() };
        node.bounds[i] = Aabb {
            min: tracer::Vec3::new(b.lower_x, b.lower_y, b.lower_z),
            max: tracer::Vec3::new(b.upper_x, b.upper_y, b.upper_z),
        };
    }
}

unsafe extern "C" fn create_leaf(
    alloc: RTCThreadLocalAllocator,
    prims: *const RTCBuildPrimitive,
    count: usize,
    user: *mut c_void,
) -> *mut c_void {
    let bytes = size_of::<Leaf>() + 4 * count;
    // SAFETY: Embree's allocator and our context.
    let p = unsafe { allocate(alloc, bytes, user) } as *mut Leaf;
    // SAFETY: `bytes` hold the header and `count` ids; Embree passes `count` primitives.
    unsafe {
        p.write(Leaf { tag: LEAF, count: count as u32 });
        let ids = (p as *mut u8).add(size_of::<Leaf>()) as *mut u32;
        for i in 0..count {
            ids.add(i).write(prims.add(i).read_unaligned().primID);
        }
    }
    p as *mut c_void
}

/// The boxes of the triangle's parts inside the primitive's box on either side of the plane, as Embree's
/// `TriangleSplitter` does (clip, then intersect with the incoming box); a side the triangle misses gets the
/// box cut at the plane, which still holds its (empty) part.
unsafe extern "C" fn split_triangle(
    prim: *const RTCBuildPrimitive,
    dim: c_uint,
    pos: f32,
    left: *mut RTCBounds,
    right: *mut RTCBounds,
    user: *mut c_void,
) {
    // SAFETY: our context and Embree's primitive, valid for the call; read without assuming its alignment.
    let (context, prim) = unsafe { (&*(user as *const Context), prim.read_unaligned()) };
    let within = Box3A {
        min: Vec3A::new(prim.lower_x, prim.lower_y, prim.lower_z),
        max: Vec3A::new(prim.upper_x, prim.upper_y, prim.upper_z),
    };
    let axis = (dim as usize).min(2);
    let cut = box_halves(&within, axis, pos);
    let halves = match context.mesh.indices.get(prim.primID as usize) {
        Some(_) => triangle_halves(&context.mesh.triangle(prim.primID as usize), &within, axis, pos),
        None => cut,
    };
    let out = |b: &Box3A| RTCBounds {
        lower_x: b.min.x,
        lower_y: b.min.y,
        lower_z: b.min.z,
        align0: 0.0,
        upper_x: b.max.x,
        upper_y: b.max.y,
        upper_z: b.max.z,
        align1: 0.0,
    };
    let pick = |i: usize| if is_empty(&halves[i]) { out(&cut[i]) } else { out(&halves[i]) };
    // SAFETY: Embree's out-pointers, valid for the call; written without assuming their alignment.
    unsafe {
        left.write_unaligned(pick(0));
        right.write_unaligned(pick(1));
    }
}

/// Copies the tree under `root` into binary [`FlatNode`]s: a node of k > 2 children becomes a balanced binary
/// subtree over them (none is expected: we ask for two).
///
/// # Safety
/// `root` and every node under it were written by this module's callbacks and are still allocated.
unsafe fn copy_out(root: *mut c_void, root_box: Aabb, triangles: usize) -> Result<(Vec<FlatNode>, Vec<u32>), String> {
    let mut nodes = vec![FlatNode { bounds: root_box, first: 0, prim_count: FlatNode::INTERIOR }];
    let mut order = Vec::with_capacity(triangles);
    // (children of one Embree node, or one node: pointer and box; the slot they fill)
    let mut stack: Vec<(Vec<(*mut c_void, Aabb)>, usize)> = vec![(vec![(root, root_box)], 0)];
    while let Some((group, slot)) = stack.pop() {
        if group.len() > 1 {
            let bounds = group.iter().fold(Aabb::EMPTY, |b, (_, c)| b.union(c));
            let first = nodes.len();
            nodes.push(nodes[slot]);
            nodes.push(nodes[slot]);
            nodes[slot] = FlatNode { bounds, first: first as u32, prim_count: FlatNode::INTERIOR };
            let (l, r) = group.split_at(group.len() / 2);
            stack.push((r.to_vec(), first + 1));
            stack.push((l.to_vec(), first));
            continue;
        }
        let (ptr, bounds) = group[0];
        if ptr.is_null() {
            return Err("rtcBuildBVH left a child unset".into());
        }
        // SAFETY: the caller's contract: a node or leaf of ours, whose tag comes first.
        match unsafe { *(ptr as *const u32) } {
            LEAF => {
                // SAFETY: a leaf header followed by its ids.
                let (count, ids) = unsafe {
                    let leaf = &*(ptr as *const Leaf);
                    (leaf.count as usize, (ptr as *const u8).add(size_of::<Leaf>()) as *const u32)
                };
                let first = order.len() as u32;
                for i in 0..count {
                    // SAFETY: `count` ids follow the header.
                    let id = unsafe { *ids.add(i) };
                    if id as usize >= triangles {
                        return Err(format!("a leaf names triangle {id} of {triangles}"));
                    }
                    order.push(id);
                }
                nodes[slot] = FlatNode { bounds, first, prim_count: count as u32 };
            }
            INNER => {
                // SAFETY: one of our inner nodes.
                let inner = unsafe { &*(ptr as *const Inner) };
                let k = inner.count as usize;
                if !(1..=MAX_CHILDREN).contains(&k) {
                    return Err(format!("a node of {k} children (at most {MAX_CHILDREN} are copied)"));
                }
                let children: Vec<_> = (0..k).map(|i| (inner.children[i], inner.bounds[i])).collect();
                nodes[slot].bounds = bounds;
                stack.push((children, slot));
            }
            tag => return Err(format!("a node of unknown tag {tag:#x}")),
        }
    }
    Ok((nodes, order))
}
