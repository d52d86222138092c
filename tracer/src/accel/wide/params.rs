//! The wide BVH's own parameters: node width, leaf block, SIMD kernel and child order.

use serde::{Deserialize, Serialize};

use crate::accel::bvh::ParamError;

/// The instruction set the traversal runs with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Kernel {
    /// The kernel measured fastest on this CPU for the tree's leaf block, resolved when the tree is built (see
    /// [`Kernel::resolve_for`]).
    Auto,
    /// Portable code, one lane at a time (the compiler may still vectorize it with the baseline ISA).
    Scalar,
    /// AVX2 and FMA: 8 lanes of f32 (4-lane nodes and blocks use 128-bit vectors).
    Avx2,
    /// AVX-512F: 16-lane leaf blocks; narrower nodes and blocks as in AVX2.
    Avx512,
}

impl Kernel {
    /// Every kernel, in the order tools list them.
    pub const ALL: [Kernel; 4] = [Kernel::Auto, Kernel::Scalar, Kernel::Avx2, Kernel::Avx512];

    /// The kebab-case name used in configs and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Kernel::Auto => "auto",
            Kernel::Scalar => "scalar",
            Kernel::Avx2 => "avx2",
            Kernel::Avx512 => "avx512",
        }
    }

    /// True when this CPU can run the kernel (`auto` always can).
    pub fn is_available(self) -> bool {
        match self {
            Kernel::Auto | Kernel::Scalar => true,
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx2 => std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma"),
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx512 => {
                Kernel::Avx2.is_available()
                    && std::arch::is_x86_feature_detected!("avx512f")
                    && std::arch::is_x86_feature_detected!("avx512vl")
            }
            #[cfg(not(target_arch = "x86_64"))]
            Kernel::Avx2 | Kernel::Avx512 => false,
        }
    }

    /// The kernels this CPU can run, auto resolved: scalar always, then AVX2 and AVX-512 where present.
    pub fn available() -> Vec<Kernel> {
        [Kernel::Scalar, Kernel::Avx2, Kernel::Avx512].into_iter().filter(|k| k.is_available()).collect()
    }

    /// The smallest leaf block `auto` runs the AVX-512 kernel for: its 16-lane sphere test needs blocks of 16.
    /// With blocks of 4 or 8 it runs the AVX2 code compiled with AVX-512F enabled, measured 0-10% slower than
    /// the AVX2 kernel on single rays (AMD Zen 4 here, Zen 5 in issue #20); with blocks of 16, 5-15% faster
    /// (`experiments/kernels.toml`, docs/tracer.md, "SIMD kernels").
    pub const AVX512_FROM_BLOCK: u32 = 16;

    /// The kernel that runs for leaf blocks of `leaf_block` spheres: `auto` becomes AVX-512 for blocks of at least
    /// [`Kernel::AVX512_FROM_BLOCK`] where the CPU has it, else AVX2 where it has that, else scalar (the fastest
    /// measured); a named kernel is itself.
    pub fn resolve_for(self, leaf_block: u32) -> Kernel {
        match self {
            Kernel::Auto if leaf_block >= Self::AVX512_FROM_BLOCK && Kernel::Avx512.is_available() => Kernel::Avx512,
            Kernel::Auto if Kernel::Avx2.is_available() => Kernel::Avx2,
            Kernel::Auto => Kernel::Scalar,
            k => k,
        }
    }
}

/// The order in which a traversal visits the children of a wide node that the ray enters.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ChildOrdering {
    /// Stored order (the binary tree's left-to-right order).
    None,
    /// Nearest entry distance first (children sorted by the slab test's entry distance).
    Distance,
    /// An order precomputed per node for each of the 8 ray-direction octants (children sorted along the octant's
    /// diagonal by box center).
    Octant,
}

impl ChildOrdering {
    /// Every ordering, in the order tools list them.
    pub const ALL: [ChildOrdering; 3] = [ChildOrdering::None, ChildOrdering::Distance, ChildOrdering::Octant];

    /// The kebab-case name used in configs and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            ChildOrdering::None => "none",
            ChildOrdering::Distance => "distance",
            ChildOrdering::Octant => "octant",
        }
    }
}

/// The order in which any-hit (occlusion) traversal visits a node's children.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum AnyHitOrdering {
    /// The [`ChildOrdering`] of nearest hits.
    #[default]
    ChildOrder,
    /// Stored order, whatever the child order: no distances sorted for a ray that stops at its first hit.
    None,
}

impl AnyHitOrdering {
    /// Every ordering, in the order tools list them.
    pub const ALL: [AnyHitOrdering; 2] = [AnyHitOrdering::ChildOrder, AnyHitOrdering::None];

    /// The kebab-case name used in configs and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            AnyHitOrdering::ChildOrder => "child-order",
            AnyHitOrdering::None => "none",
        }
    }

    fn is_child_order(&self) -> bool {
        *self == AnyHitOrdering::ChildOrder
    }
}

/// Parameters of a wide BVH (the binary tree it is collapsed from has its own [`crate::accel::BvhParams`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct WideParams {
    /// Children per node, in [`WideParams::WIDTHS`].
    pub width: u32,
    /// Spheres a leaf tests at once (SIMD lanes of one leaf block), in [`WideParams::LEAF_BLOCKS`].
    pub leaf_block: u32,
    /// The instruction set; see [`Kernel`].
    pub kernel: Kernel,
    /// The child visiting order; see [`ChildOrdering`].
    pub order: ChildOrdering,
    /// The child visiting order of any-hit rays; see [`AnyHitOrdering`]. Left out when serialized at its default.
    #[serde(skip_serializing_if = "AnyHitOrdering::is_child_order")]
    pub any_hit_order: AnyHitOrdering,
    /// Rays a batch traces together, in [`WideParams::PACKETS`]: 1 traces them one by one, 8 or 16 in packets
    /// with an active mask (see [`super::packet`]), 64 in frustum-culled packets of an 8×8 tile of camera rays
    /// (see [`super::tile`]). Left out when serialized at 1.
    #[serde(skip_serializing_if = "WideParams::is_single")]
    pub packet: u32,
    /// Primitives the binary build's SAH counts a leaf in blocks of, a node of at most that many always a leaf;
    /// in [`WideParams::SAH_BLOCKS`], capped at `leaf_block` (so the default, 16, is the leaf block). The collapse still makes every subtree of at
    /// most `leaf_block` primitives one leaf: a smaller block only changes which primitives share it. Left out when
    /// serialized at 16.
    #[serde(default = "WideParams::widest_sah_block", skip_serializing_if = "WideParams::is_widest_sah_block")]
    pub sah_block: u32,
}

impl Default for WideParams {
    fn default() -> Self {
        Self {
            width: 8,
            leaf_block: 8,
            kernel: Kernel::Auto,
            order: ChildOrdering::Distance,
            any_hit_order: AnyHitOrdering::ChildOrder,
            packet: 1,
            sah_block: 16,
        }
    }
}

impl WideParams {
    /// Allowed `width` values.
    pub const WIDTHS: [u32; 2] = [4, 8];
    /// Allowed `leaf_block` values.
    pub const LEAF_BLOCKS: [u32; 3] = [4, 8, 16];
    /// Allowed `sah_block` values.
    pub const SAH_BLOCKS: [u32; 5] = [1, 2, 4, 8, 16];
    /// Allowed `packet` values.
    pub const PACKETS: [u32; 4] = [1, 8, 16, 64];

    fn is_single(packet: &u32) -> bool {
        *packet == 1
    }

    fn widest_sah_block() -> u32 {
        16
    }

    fn is_widest_sah_block(block: &u32) -> bool {
        *block == 16
    }

    /// The block the binary build's SAH counts leaves in: `sah_block`, at most the leaf block.
    pub fn build_block(&self) -> u32 {
        self.sah_block.min(self.leaf_block)
    }

    /// True for the default parameters (serialized parameters of other structures leave them out).
    pub fn is_default(&self) -> bool {
        *self == Self::default()
    }

    /// Checks every value, and that this CPU can run the kernel; builders refuse invalid parameters.
    pub fn validate(&self) -> Result<(), ParamError> {
        let list = |values: &[u32]| values.iter().map(u32::to_string).collect::<Vec<_>>().join(", ");
        if !Self::WIDTHS.contains(&self.width) {
            return Err(ParamError { key: "width", allowed: list(&Self::WIDTHS), found: self.width.to_string() });
        }
        if !Self::LEAF_BLOCKS.contains(&self.leaf_block) {
            let found = self.leaf_block.to_string();
            return Err(ParamError { key: "leaf_block", allowed: list(&Self::LEAF_BLOCKS), found });
        }
        if !Self::SAH_BLOCKS.contains(&self.sah_block) {
            let found = self.sah_block.to_string();
            return Err(ParamError { key: "sah_block", allowed: list(&Self::SAH_BLOCKS), found });
        }
        if !Self::PACKETS.contains(&self.packet) {
            return Err(ParamError { key: "packet", allowed: list(&Self::PACKETS), found: self.packet.to_string() });
        }
        if !self.kernel.is_available() {
            let names = std::iter::once(Kernel::Auto).chain(Kernel::available()).map(Kernel::name).collect::<Vec<_>>();
            let allowed = format!("{} (this CPU lacks {})", names.join(", "), self.kernel.name());
            return Err(ParamError { key: "kernel", allowed, found: self.kernel.name().to_owned() });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn out_of_range_values_name_the_allowed_ones() {
        let e = WideParams { width: 6, ..WideParams::default() }.validate().unwrap_err();
        assert_eq!((e.key, e.allowed.as_str()), ("width", "4, 8"));
        let e = WideParams { leaf_block: 2, ..WideParams::default() }.validate().unwrap_err();
        assert_eq!((e.key, e.allowed.as_str()), ("leaf_block", "4, 8, 16"));
        let e = WideParams { packet: 4, ..WideParams::default() }.validate().unwrap_err();
        assert_eq!((e.key, e.allowed.as_str()), ("packet", "1, 8, 16, 64"));
        let e = WideParams { sah_block: 3, ..WideParams::default() }.validate().unwrap_err();
        assert_eq!((e.key, e.allowed.as_str()), ("sah_block", "1, 2, 4, 8, 16"));
        assert_eq!(WideParams { sah_block: 16, leaf_block: 8, ..WideParams::default() }.build_block(), 8);
        assert!(WideParams::default().validate().is_ok());
    }

    #[test]
    fn auto_resolves_to_the_kernel_measured_fastest_for_the_leaf_block() {
        for block in WideParams::LEAF_BLOCKS {
            let k = Kernel::Auto.resolve_for(block);
            assert_ne!(k, Kernel::Auto);
            assert!(k.is_available());
            let widest_useful = if block >= 16 { Kernel::available().last().copied() } else { None };
            let want = widest_useful.unwrap_or(if Kernel::Avx2.is_available() { Kernel::Avx2 } else { Kernel::Scalar });
            assert_eq!(k, want, "blocks of {block}");
            assert_eq!(Kernel::Scalar.resolve_for(block), Kernel::Scalar);
            assert_eq!(Kernel::Avx2.resolve_for(block), Kernel::Avx2);
        }
    }

    #[test]
    fn a_kernel_this_cpu_lacks_is_refused_by_name() {
        for kernel in [Kernel::Avx2, Kernel::Avx512] {
            let r = WideParams { kernel, ..WideParams::default() }.validate();
            if kernel.is_available() {
                assert!(r.is_ok());
            } else {
                let e = r.unwrap_err();
                assert_eq!((e.key, e.found.as_str()), ("kernel", kernel.name()));
                assert!(e.to_string().contains("lacks"), "{e}");
            }
        }
    }

    #[test]
    fn serializes_in_kebab_case_and_fills_defaults() {
        let p: WideParams = serde_json::from_str(r#"{"width": 4, "kernel": "avx512", "order": "octant"}"#).unwrap();
        assert_eq!(
            p,
            WideParams { width: 4, kernel: Kernel::Avx512, order: ChildOrdering::Octant, ..WideParams::default() }
        );
        let text = serde_json::to_string(&WideParams::default()).unwrap();
        assert_eq!(text, r#"{"width":8,"leaf_block":8,"kernel":"auto","order":"distance"}"#);
        assert!(serde_json::from_str::<WideParams>(r#"{"widht": 4}"#).is_err());
        let packets = WideParams { packet: 16, ..WideParams::default() };
        let text = serde_json::to_string(&packets).unwrap();
        assert_eq!(text, r#"{"width":8,"leaf_block":8,"kernel":"auto","order":"distance","packet":16}"#);
        assert_eq!(serde_json::from_str::<WideParams>(&text).unwrap(), packets);
        let unsorted = WideParams { any_hit_order: AnyHitOrdering::None, ..WideParams::default() };
        let text = serde_json::to_string(&unsorted).unwrap();
        assert_eq!(text, r#"{"width":8,"leaf_block":8,"kernel":"auto","order":"distance","any_hit_order":"none"}"#);
        assert_eq!(serde_json::from_str::<WideParams>(&text).unwrap(), unsorted);
    }
}
