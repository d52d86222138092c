// A C ABI over tinybvh 1.6.8 (the single header bundled by the tinybvh-rs crate), for bvhlab's `peers::tinybvh`.
//
// `build.rs` compiles this file once per ISA level with `-DTB_VARIANT=vN -march=x86-64-vN`. The header goes into
// the namespace `tinybvh_vN` (the macro below renames its one namespace) and every exported function is named
// `tinybvh_vN_*`, so the variants coexist in one binary; `build.rs` also makes every other symbol of a variant
// local, so that no inline function or template instance (the standard library's included) is shared between
// variants compiled for different CPUs.
//
// Rays and hits cross the boundary as this file's own plain structs (`TbRay`, `TbHit`, `TbStats`; sizes asserted
// here and in mod.rs); tinybvh's `Ray` (128 bytes, 64-byte aligned) never leaves C++. See mod.rs for the mapping
// of our rays (t_min, non-unit directions, exclusive t_max) onto tinybvh's.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <new>
#include <vector>

#ifndef TB_VARIANT
#error "TB_VARIANT (v2, v3 or v4) must be defined"
#endif
#define TB_CAT2(a, b) a##b
#define TB_CAT(a, b) TB_CAT2(a, b)
#define TB_NS TB_CAT(tinybvh_, TB_VARIANT)
#define TB_FN(name) TB_CAT(TB_CAT(TB_NS, _), name)

#define tinybvh TB_NS
#define TINYBVH_IMPLEMENTATION
#include "tiny_bvh.h"
#undef tinybvh

using namespace TB_NS;

// tinybvh's own ray, for the record (what the tinybvh-rs 0.1.0-beta.3 wrapper gets wrong: it declares 64 bytes).
static_assert(sizeof(Ray) == 128 && alignof(Ray) == 64, "tinybvh 1.6.8 Ray layout changed");
static_assert(sizeof(bvhvec4) == 16 && alignof(bvhvec4) == 16, "tinybvh bvhvec4 layout changed");

extern "C" {

// One ray as bvhlab passes it: points origin + t * dir for t_min < t < t_max (dir of any length).
struct TbRay {
    float origin[3];
    float dir[3];
    float t_min;
    float t_max;
};
static_assert(sizeof(TbRay) == 32 && alignof(TbRay) == 4, "TbRay must match mod.rs");

// A closest hit: t in units of the ray's dir, prim the triangle index; prim == UINT32_MAX for a miss.
struct TbHit {
    float t;
    uint32_t prim;
};
static_assert(sizeof(TbHit) == 8 && alignof(TbHit) == 4, "TbHit must match mod.rs");

// What a build reports; bytes are those the traversal reads.
struct TbStats {
    uint64_t nodes;
    uint64_t leaves;
    uint64_t depth;
    uint64_t bytes;
    double sah_cost;
};
static_assert(sizeof(TbStats) == 40 && alignof(TbStats) == 8, "TbStats must match mod.rs");

// The sizes this variant was compiled with, checked by mod.rs's tests against its own.
// One node of the plain layout's binary tree, as tinybvh stores it (BVH::BVHNode): an interior node's children
// are nodes left_first and left_first + 1; a leaf (tri_count > 0) names tri_count primitive indices from left_first.
struct TbNode {
    float min[3];
    uint32_t left_first;
    float max[3];
    uint32_t tri_count;
};
static_assert(sizeof(TbNode) == 32 && alignof(TbNode) == 4, "TbNode must match mod.rs");

struct TbAbi {
    uint32_t ray_size, ray_align, hit_size, hit_align, stats_size, stats_align;
    uint32_t tiny_ray_size, tiny_ray_align;
    uint32_t version;  // major * 10000 + minor * 100 + sub
};

}  // extern "C"

namespace {

enum : uint32_t { LAYOUT_PLAIN = 0, LAYOUT_BVH4_CPU = 1, LAYOUT_BVH8_CPU = 2 };
enum : uint32_t { QUALITY_DEFAULT = 0, QUALITY_HQ = 1 };
enum : int32_t { OK = 0, ERR_LAYOUT = 1, ERR_ARGS = 2, ERR_DEPTH = 3, ERR_ALLOC = 4 };

// Layouts this variant's compile flags give tinybvh (BVH4_CPU needs SSE4.2; BVH8_CPU AVX2 and FMA).
constexpr uint32_t layout_mask() {
    uint32_t m = 1u << LAYOUT_PLAIN;
#if defined BVH_USESSE && !defined BVH_USENEON
    m |= 1u << LAYOUT_BVH4_CPU;
#endif
#if defined BVH_USEAVX2 && !defined BVH_USENEON
    m |= 1u << LAYOUT_BVH8_CPU;
#endif
    return m;
}

// Deepest stack any tinybvh routine we call may need, as binary-tree depth: BVH::SplitLeafs and the binary
// IsOccluded keep 64 entries; the wide conversions and traversals (128 and 256) need at most 2 per binary level.
constexpr uint32_t MAX_DEPTH = 60;

// Depth of the binary tree counting the levels BVH::SplitLeafs(split) adds under leaves of more than `split`
// primitives (0: none), and its node and leaf counts and unit-cost SAH (traversal 1, one per primitive).
// Surface area of a box (0 for an empty or inverted one).
double area(const bvhvec3& lo, const bvhvec3& hi) {
    const double x = std::fmax(hi.x - lo.x, 0.0f), y = std::fmax(hi.y - lo.y, 0.0f), z = std::fmax(hi.z - lo.z, 0.0f);
    return 2 * (x * y + y * z + z * x);
}

struct BinaryWalk {
    uint64_t nodes = 0, leaves = 0, depth = 0;
    double sah = 0;
};
BinaryWalk walk_binary(const BVH& bvh, uint32_t split) {
    BinaryWalk w;
    const BVH::BVHNode& root = bvh.bvhNode[0];
    double root_area = area(root.aabbMin, root.aabbMax);
    if (!(root_area > 0)) root_area = 1;
    std::vector<std::pair<uint32_t, uint32_t>> stack{{0u, 0u}};
    while (!stack.empty()) {
        auto [i, d] = stack.back();
        stack.pop_back();
        const BVH::BVHNode& n = bvh.bvhNode[i];
        w.nodes++;
        const double a = area(n.aabbMin, n.aabbMax) / root_area;
        if (n.isLeaf()) {
            w.leaves++;
            w.sah += a * n.triCount;
            uint32_t extra = split && n.triCount > split ? (n.triCount - 1) / split : 0;
            if (d + extra > w.depth) w.depth = d + extra;
        } else {
            w.sah += a;
            stack.push_back({n.leftFirst, d + 1});
            stack.push_back({n.leftFirst + 1, d + 1});
        }
    }
    return w;
}

// Node, leaf and depth counts of an M-wide tree (its leaves: child slots holding triangles).
template <int M> void walk_wide(const MBVH<M>& mbvh, TbStats& s) {
    s.nodes = s.leaves = s.depth = 0;
    std::vector<std::pair<uint32_t, uint32_t>> stack{{0u, 0u}};
    while (!stack.empty()) {
        auto [i, d] = stack.back();
        stack.pop_back();
        const auto& n = mbvh.mbvhNode[i];
        if (n.isLeaf()) {
            s.leaves++;
            continue;
        }
        s.nodes++;
        if (d > s.depth) s.depth = d;
        for (uint32_t c = 0; c < n.childCount; c++) stack.push_back({n.child[c], d + 1});
    }
    s.sah_cost = 0;  // the binary cost model does not apply to wide nodes
}

// A built structure with the triangle soup it was built over (tinybvh keeps a pointer to the vertices).
struct Accel {
    uint32_t layout = LAYOUT_PLAIN;
    bvhvec4* verts = nullptr;  // 3 per triangle, 16-byte aligned (tinybvh reads them as __m128)
    uint32_t tris = 0;
    BVH plain;
    BVH4_CPU bvh4;
    BVH8_CPU bvh8;
    ~Accel() { free64(verts); }
};

// Builds tinybvh's binary BVH over the soup the way the layout's own Build/BuildHQ does.
void build_binary(BVH& bvh, const bvhvec4* verts, uint32_t tris, uint32_t layout, uint32_t quality) {
    if (quality == QUALITY_HQ) {
        bvh.BuildHQ(verts, tris);
    } else if (layout == LAYOUT_PLAIN) {
        bvh.Build(verts, tris);  // the reference binned builder BVH::Build
    } else {
#ifdef BVH_USEAVX
        bvh.BuildAVX(verts, tris);  // what BVH4_CPU/BVH8_CPU::Build call (BuildDefault) with AVX
#else
        bvh.Build(verts, tris);  // ... and without
#endif
    }
}

// Where a ray with `t_min` starts for tinybvh: at the float above t_min (tinybvh's plain layout accepts t >= 0,
// so t > t_min exactly, up to the rounding of the moved origin); 0 (the origin itself) when t_min <= 0.
inline float start_of(const TbRay& r) { return r.t_min > 0 ? std::nextafter(r.t_min, INFINITY) : 0.0f; }

// The ray in tinybvh's form: tinybvh's constructor normalizes the direction (its hits are in units of the unit
// direction, `len` of ours), and has no t_min, so the origin moves to start_of(r). False when the ray cannot hit.
inline bool to_tiny(const TbRay& r, Ray& out, float& len, bool occlusion) {
    const bvhvec3 d(r.dir[0], r.dir[1], r.dir[2]);
    len = tinybvh_length(d);
    bvhvec3 o(r.origin[0], r.origin[1], r.origin[2]);
    float t_max = r.t_max;
    const float start = start_of(r);
    if (start > 0) {
        o = o + d * start;
        t_max = r.t_max - start;
    }
    float t = t_max * len;
    if (!(len > 0) || !(t > 0) || !std::isfinite(o.x + o.y + o.z) || !std::isfinite(len)) return false;
    if (t > BVH_FAR) t = BVH_FAR;
    // IsOccluded accepts a hit at t == hit.t; ours excludes t_max.
    if (occlusion) t = std::nextafter(t, 0.0f);
    out = Ray(o, d, t);
    return true;
}

inline TbHit intersect_one(const Accel& a, const TbRay& r) {
    TbHit miss{INFINITY, UINT32_MAX};
    if (a.tris == 0) return miss;
    Ray ray;
    float len;
    if (!to_tiny(r, ray, len, false)) return miss;
    const float t_max = ray.hit.t;
    switch (a.layout) {
        case LAYOUT_PLAIN: a.plain.Intersect(ray); break;
#if defined BVH_USESSE
        case LAYOUT_BVH4_CPU: a.bvh4.Intersect(ray); break;
#endif
#if defined BVH_USEAVX2
        case LAYOUT_BVH8_CPU: a.bvh8.Intersect(ray); break;
#endif
        default: return miss;
    }
    // A miss leaves hit.t at t_max; the plain layout also accepts a hit at exactly t_max, which we exclude.
    if (!(ray.hit.t < t_max)) return miss;
    const float t = ray.hit.t / len, start = start_of(r);
    return TbHit{start > 0 ? start + t : t, ray.hit.prim};
}

inline bool occluded_one(const Accel& a, const TbRay& r) {
    if (a.tris == 0) return false;
    Ray ray;
    float len;
    if (!to_tiny(r, ray, len, true)) return false;
    switch (a.layout) {
        case LAYOUT_PLAIN: return a.plain.IsOccluded(ray);
#if defined BVH_USESSE
        case LAYOUT_BVH4_CPU: return a.bvh4.IsOccluded(ray);
#endif
#if defined BVH_USEAVX2
        case LAYOUT_BVH8_CPU: return a.bvh8.IsOccluded(ray);
#endif
        default: return false;
    }
}

}  // namespace

extern "C" {

// The sizes and version this variant was compiled with.
void TB_FN(abi)(TbAbi* out) {
    *out = TbAbi{sizeof(TbRay), alignof(TbRay), sizeof(TbHit), alignof(TbHit), sizeof(TbStats), alignof(TbStats),
                 sizeof(Ray), alignof(Ray),
                 TINY_BVH_VERSION_MAJOR * 10000 + TINY_BVH_VERSION_MINOR * 100 + TINY_BVH_VERSION_SUB};
}

// Bit i set: layout i is compiled into this variant.
uint32_t TB_FN(layouts)(void) { return layout_mask(); }

// Builds `layout` over `tris` triangles (`indices`: 3 per triangle into `positions`: xyz triples, all in range,
// checked by the caller). On success (OK) `*out` owns the structure (free with `_free`), `stats` describes it.
int32_t TB_FN(build)(const float* positions, const uint32_t* indices, uint32_t tris, uint32_t layout,
                     uint32_t quality, void** out, TbStats* stats) {
    *out = nullptr;
    *stats = TbStats{0, 0, 0, 0, 0.0};
    if (layout > LAYOUT_BVH8_CPU || !(layout_mask() & (1u << layout))) return ERR_LAYOUT;
    if (quality > QUALITY_HQ || tris > (1u << 26)) return ERR_ARGS;
    Accel* a = new (std::nothrow) Accel();
    if (!a) return ERR_ALLOC;
    a->layout = layout;
    a->tris = tris;
    if (tris == 0) {  // tinybvh exits the process on an empty build: an empty structure misses every ray
        *out = a;
        return OK;
    }
    a->verts = static_cast<bvhvec4*>(malloc64(sizeof(bvhvec4) * 3 * size_t(tris)));
    if (!a->verts) {
        delete a;
        return ERR_ALLOC;
    }
    for (size_t i = 0; i < 3 * size_t(tris); i++) {
        const float* p = positions + 3 * size_t(indices[i]);
        a->verts[i] = bvhvec4(p[0], p[1], p[2], 0.0f);
    }
    int32_t status = OK;
    try {
        if (layout == LAYOUT_PLAIN) {
            build_binary(a->plain, a->verts, tris, layout, quality);
            const BinaryWalk w = walk_binary(a->plain, 0);
            if (w.depth > MAX_DEPTH) status = ERR_DEPTH;
            *stats = TbStats{w.nodes, w.leaves, w.depth,
                             uint64_t(a->plain.usedNodes) * sizeof(BVH::BVHNode) + uint64_t(a->plain.idxCount) * 4 +
                                 uint64_t(tris) * 3 * sizeof(bvhvec4),
                             w.sah};
        }
#if defined BVH_USESSE
        else if (layout == LAYOUT_BVH4_CPU) {
            // BVH4_CPU::Build / BuildHQ, step by step, so the depth is checked before the conversions.
            BVH4_CPU& b = a->bvh4;
            b.bvh4.bvh.context = b.bvh4.context = b.context;
            build_binary(b.bvh4.bvh, a->verts, tris, layout, quality);
            if (walk_binary(b.bvh4.bvh, 4).depth > MAX_DEPTH) {
                status = ERR_DEPTH;
            } else {
                b.bvh4.bvh.PrepareBuild4_8();
                b.bvh4.ConvertFrom(b.bvh4.bvh, true);
                b.ConvertFrom(b.bvh4);
                walk_wide(b.bvh4, *stats);
                stats->bytes = uint64_t(b.usedBlocks) * 64;
            }
        }
#endif
#if defined BVH_USEAVX2
        else if (layout == LAYOUT_BVH8_CPU) {
            // BVH8_CPU::Build / BuildHQ, step by step (as above).
            BVH8_CPU& b = a->bvh8;
            b.bvh8.bvh.context = b.bvh8.context = b.context;
            build_binary(b.bvh8.bvh, a->verts, tris, layout, quality);
            if (walk_binary(b.bvh8.bvh, 4).depth > MAX_DEPTH) {
                status = ERR_DEPTH;
            } else {
                b.bvh8.bvh.PrepareBuild4_8();
                b.bvh8.bvh.Compact();
                b.bvh8.ConvertFrom(b.bvh8.bvh, true);
                b.ConvertFrom(b.bvh8);
                walk_wide(b.bvh8, *stats);
                stats->bytes = uint64_t(b.usedBlocks) * 64;
            }
        }
#endif
    } catch (...) {
        status = ERR_ALLOC;
    }
    if (status != OK) {
        delete a;
        return status;
    }
    *out = a;
    return OK;
}

// Sizes of a plain-layout structure's binary tree: nodes in use and primitive indices (ERR_LAYOUT for another
// layout; both 0 for an empty structure).
int32_t TB_FN(plain_tree_size)(const void* accel, uint32_t* nodes, uint32_t* indices) {
    const Accel& a = *static_cast<const Accel*>(accel);
    *nodes = *indices = 0;
    if (a.layout != LAYOUT_PLAIN) return ERR_LAYOUT;
    if (a.tris == 0) return OK;
    *nodes = a.plain.usedNodes;
    *indices = a.plain.idxCount;
    return OK;
}

// Copies that tree: `nodes` and `indices` hold the counts `_plain_tree_size` gave (node 1 is tinybvh's unused slot).
void TB_FN(plain_tree_copy)(const void* accel, TbNode* nodes, uint32_t* indices) {
    const Accel& a = *static_cast<const Accel*>(accel);
    if (a.layout != LAYOUT_PLAIN || a.tris == 0) return;
    for (uint32_t i = 0; i < a.plain.usedNodes; i++) {
        const BVH::BVHNode& n = a.plain.bvhNode[i];
        nodes[i] = TbNode{{n.aabbMin.x, n.aabbMin.y, n.aabbMin.z}, n.leftFirst,
                          {n.aabbMax.x, n.aabbMax.y, n.aabbMax.z}, n.triCount};
    }
    std::memcpy(indices, a.plain.primIdx, size_t(a.plain.idxCount) * sizeof(uint32_t));
}

// Frees a structure `_build` returned (null is ignored).
void TB_FN(free)(void* accel) { delete static_cast<Accel*>(accel); }

// The closest hit of one ray.
TbHit TB_FN(intersect)(const void* accel, const TbRay* ray) {
    return intersect_one(*static_cast<const Accel*>(accel), *ray);
}

// True when any triangle is hit (tinybvh's IsOccluded).
bool TB_FN(occluded)(const void* accel, const TbRay* ray) {
    return occluded_one(*static_cast<const Accel*>(accel), *ray);
}

// Closest hits of `n` rays.
void TB_FN(intersect_batch)(const void* accel, const TbRay* rays, size_t n, TbHit* out) {
    const Accel& a = *static_cast<const Accel*>(accel);
    for (size_t i = 0; i < n; i++) out[i] = intersect_one(a, rays[i]);
}

// Occlusion of `n` rays (1 occluded, 0 not).
void TB_FN(occluded_batch)(const void* accel, const TbRay* rays, size_t n, uint8_t* out) {
    const Accel& a = *static_cast<const Accel*>(accel);
    for (size_t i = 0; i < n; i++) out[i] = occluded_one(a, rays[i]) ? 1 : 0;
}

}  // extern "C"
