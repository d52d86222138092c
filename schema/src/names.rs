//! Named choices: every enum a setting can take, with its kebab-case name (the only spelling of the name
//! outside its declaration is the config, the CSV and the command line).

use std::fmt;

use serde::{Deserialize, Serialize};
use tracer::accel::wide::{AnyHitOrdering, ChildOrdering, Kernel, WideParams};
use tracer::accel::{AccelKind, Split, Traversal};
use tracer::executor::StrategyKind;
use tracer::geometry::TriangleTest;
use tracer::rays::RayKind;
use tracer::scene::{SceneKind, View};

/// An enum of named choices.
pub trait Named: Copy + Eq + fmt::Debug + Send + Sync + 'static {
    /// Every choice, in the order tools list them.
    const ALL: &'static [Self];
    /// The kebab-case name used in configs, rows and on the command line.
    fn name(self) -> &'static str;
    /// The choice called `name`.
    fn from_name(name: &str) -> Option<Self> {
        Self::ALL.iter().copied().find(|c| c.name() == name)
    }
    /// Every name, comma-separated (for "allowed: …" messages).
    fn names() -> String {
        Self::ALL.iter().map(|c| c.name()).collect::<Vec<_>>().join(", ")
    }
}

/// Implements [`Named`] for an enum that has `ALL` and `name()` of its own.
macro_rules! named_by_inherent {
    ($($t:ty),*) => {$(
        impl Named for $t {
            const ALL: &'static [Self] = &<$t>::ALL;
            fn name(self) -> &'static str {
                <$t>::name(self)
            }
        }
    )*};
}

named_by_inherent!(
    AccelKind,
    Split,
    Traversal,
    StrategyKind,
    SceneKind,
    RayKind,
    Kernel,
    ChildOrdering,
    AnyHitOrdering,
    TriangleTest,
    View
);

/// Declares a kebab-case enum with its names, `ALL`, `Display` and `Named`.
macro_rules! named_enum {
    ($(#[doc = $doc:literal])* $name:ident { $($(#[doc = $vdoc:literal])* $variant:ident = $text:literal,)+ }) => {
        $(#[doc = $doc])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
        pub enum $name {
            $($(#[doc = $vdoc])* #[serde(rename = $text)] $variant,)+
        }
        impl Named for $name {
            const ALL: &'static [Self] = &[$($name::$variant,)+];
            fn name(self) -> &'static str {
                match self {
                    $($name::$variant => $text,)+
                }
            }
        }
        impl fmt::Display for $name {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str(self.name())
            }
        }
    };
}

named_enum! {
    /// Which peer backend to run.
    PeerKind {
        /// obvhs 0.4's binary BVH.
        ObvhsBvh2 = "obvhs-bvh2",
        /// obvhs 0.4's compressed wide BVH8.
        ObvhsCwbvh = "obvhs-cwbvh",
        /// Embree 4 queried one ray at a time (`rtcIntersect1` / `rtcOccluded1`).
        Embree = "embree",
        /// Embree 4 queried in packets of 16 rays (`rtcIntersect16`) or 8 (`rtcIntersect8`), by `embree_packet`.
        EmbreePackets = "embree-packets",
        /// tinybvh 1.6.8 through the harness's own shim (triangle scenes only), layout by `tinybvh_layout`.
        TinyBvh = "tinybvh",
        /// Not a peer: every ray misses at once, so its trace time is the harness's own cost per ray (never validated).
        Null = "null",
    }
}

impl PeerKind {
    /// True for the peers that need the Embree library.
    pub fn needs_embree(self) -> bool {
        matches!(self, PeerKind::Embree | PeerKind::EmbreePackets)
    }

    /// True for obvhs's structures.
    pub fn is_obvhs(self) -> bool {
        matches!(self, PeerKind::ObvhsBvh2 | PeerKind::ObvhsCwbvh)
    }
}

named_enum! {
    /// How a configuration's answers compared with the reference's (the `validation` column).
    ValidationStatus {
        /// Every disagreement was tolerated by f64 brute force (or there was none): timed.
        Exact = "exact",
        /// Some disagreement was not: recorded once, never timed.
        Failed = "FAILED",
        /// Not compared: the backend answers nothing (the `null` backend).
        Unchecked = "unchecked",
    }
}

#[allow(clippy::derivable_impls)]
impl Default for ValidationStatus {
    fn default() -> Self {
        ValidationStatus::Unchecked
    }
}

named_enum! {
    /// Whose answers f64 brute force showed wrong on the rays counted as mismatches (the `wrong_side` column).
    WrongSide {
        /// No mismatch.
        Neither = "-",
        /// The backend's.
        Backend = "backend",
        /// The reference's (every configuration validated against it fails).
        Reference = "reference",
        /// Both.
        Both = "both",
    }
}

impl WrongSide {
    /// The side of the flags: whether the backend's and whether the reference's answers were shown wrong.
    pub fn of(backend_wrong: bool, reference_wrong: bool) -> Self {
        match (backend_wrong, reference_wrong) {
            (false, false) => WrongSide::Neither,
            (true, false) => WrongSide::Backend,
            (false, true) => WrongSide::Reference,
            (true, true) => WrongSide::Both,
        }
    }
}

#[allow(clippy::derivable_impls)]
impl Default for WrongSide {
    fn default() -> Self {
        WrongSide::Neither
    }
}

named_enum! {
    /// obvhs 0.4's build presets: each is `BvhBuildParams::<name>_build()` (`medium` is "around Embree's build
    /// time, faster traversal").
    ObvhsQuality { Fastest = "fastest", VeryFast = "very-fast", Fast = "fast", Medium = "medium", Slow = "slow", VerySlow = "very-slow", }
}

named_enum! {
    /// Embree's BVH build quality (`RTC_BUILD_QUALITY_*`).
    EmbreeQuality {
        /// `RTC_BUILD_QUALITY_LOW`.
        Low = "low",
        /// `RTC_BUILD_QUALITY_MEDIUM` (Embree's default).
        Medium = "medium",
        /// `RTC_BUILD_QUALITY_HIGH`.
        High = "high",
    }
}

named_enum! {
    /// The instruction set Embree is pinned to (`isa=` in the device config); `default` lets Embree pick the best
    /// the CPU has.
    EmbreeIsa { Default = "default", Sse2 = "sse2", Sse42 = "sse4.2", Avx = "avx", Avx2 = "avx2", Avx512 = "avx512", }
}

impl EmbreeIsa {
    /// The `isa=` value to pin, `None` for [`EmbreeIsa::Default`].
    pub fn pinned(self) -> Option<&'static str> {
        (self != EmbreeIsa::Default).then(|| self.name())
    }
}

// `named_enum!` declares the variants; the defaults are chosen here rather than with `#[default]` inside it.
#[allow(clippy::derivable_impls)]
impl Default for ObvhsQuality {
    fn default() -> Self {
        ObvhsQuality::Medium
    }
}

#[allow(clippy::derivable_impls)]
impl Default for EmbreeQuality {
    fn default() -> Self {
        EmbreeQuality::Medium
    }
}

/// The accelerator of a configuration: one of the tracer's structures or a peer's.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Accel {
    /// The tracer's structure.
    Ours(AccelKind),
    /// A peer backend.
    Peer(PeerKind),
}

impl Named for Accel {
    /// The tracer's structures, then every peer: a peer is one entry in [`PeerKind`].
    const ALL: &'static [Self] = &{
        const OURS: &[AccelKind] = &AccelKind::ALL;
        const PEERS: &[PeerKind] = <PeerKind as Named>::ALL;
        let mut all = [Accel::Ours(AccelKind::List); OURS.len() + PEERS.len()];
        let mut i = 0;
        while i < all.len() {
            all[i] = if i < OURS.len() { Accel::Ours(OURS[i]) } else { Accel::Peer(PEERS[i - OURS.len()]) };
            i += 1;
        }
        all
    };
    fn name(self) -> &'static str {
        match self {
            Accel::Ours(k) => k.name(),
            Accel::Peer(p) => p.name(),
        }
    }
}

impl Accel {
    /// The peer, if this is one.
    pub fn peer(self) -> Option<PeerKind> {
        match self {
            Accel::Peer(p) => Some(p),
            Accel::Ours(_) => None,
        }
    }

    /// True for the tracer's trees (`bvh`, `flat-bvh`, and `wide-bvh`, which collapses the same binary tree): the
    /// tree's build settings apply.
    pub fn is_tree(self) -> bool {
        matches!(self, Accel::Ours(AccelKind::Bvh | AccelKind::FlatBvh | AccelKind::WideBvh))
    }

    /// True for the binary trees (`bvh`, `flat-bvh`): their traversal order applies (the wide BVH has its own).
    pub fn is_binary_tree(self) -> bool {
        matches!(self, Accel::Ours(AccelKind::Bvh | AccelKind::FlatBvh))
    }

    /// True for the wide BVH: its node width, leaf block, SIMD kernel and child order apply.
    pub fn is_wide(self) -> bool {
        self == Accel::Ours(AccelKind::WideBvh)
    }
}

/// Declares a setting that takes one of a few integers (written as the integer in configs and rows).
macro_rules! int_choice {
    ($(#[doc = $doc:literal])* $name:ident = $values:expr) => {
        $(#[doc = $doc])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub struct $name(pub u32);

        impl $name {
            /// Every allowed value, ascending.
            pub const VALUES: &'static [u32] = &$values;

            /// The value `n`, if allowed.
            pub fn new(n: u32) -> Option<$name> {
                Self::VALUES.contains(&n).then_some($name(n))
            }
        }

        impl fmt::Display for $name {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                write!(f, "{}", self.0)
            }
        }
    };
}

int_choice! {
    /// Children per node of the wide BVH (`WideParams::WIDTHS`).
    NodeWidth = WideParams::WIDTHS
}

int_choice! {
    /// Spheres per SIMD leaf block of the wide BVH (`WideParams::LEAF_BLOCKS`).
    LeafBlock = WideParams::LEAF_BLOCKS
}

int_choice! {
    /// Primitives the binary build's SAH counts leaves in blocks of (`WideParams::SAH_BLOCKS`, at most the leaf block).
    SahBlock = WideParams::SAH_BLOCKS
}

int_choice! {
    /// Rays of `embree-packets`' queries: 8 (`rtcIntersect8`) or 16 (`rtcIntersect16`).
    EmbreePacket = [8, 16]
}

named_enum! {
    /// How the wide BVH traces the rays of a ray set together (the tracer's `WideParams::packet`).
    Packet {
        /// One ray at a time.
        Single = "single",
        /// Packets of 8 rays with an active mask.
        Masked8 = "masked-8",
        /// Packets of 16 rays with an active mask.
        Masked16 = "masked-16",
        /// Frustum-culled packets of an 8×8 tile of camera rays.
        Tile8x8 = "tile-8x8",
    }
}

impl Packet {
    /// The rays traced together (`WideParams::PACKETS`), as the integer `packet_size` of earlier rows spelled it.
    pub fn rays(self) -> u32 {
        match self {
            Packet::Single => 1,
            Packet::Masked8 => 8,
            Packet::Masked16 => 16,
            Packet::Tile8x8 => 64,
        }
    }

    /// The grouping that traces `rays` together.
    pub fn of_rays(rays: u32) -> Option<Packet> {
        Packet::ALL.iter().copied().find(|p| p.rays() == rays)
    }
}

/// Where a configuration's primitives come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SceneName {
    /// One of the tracer's sphere generators.
    Generated(SceneKind),
    /// The experiment's sphere file (`sweep.sphere_file`).
    SphereFile,
    /// The random-spheres scene of `objects` spheres, each tessellated into a closed UV sphere of
    /// [`SceneName::SEGMENTS`] slices.
    TessellatedSpheres,
    /// `objects` random triangles in the random-spheres scene's box.
    RandomTriangles,
    /// The triangle mesh named by the `mesh` setting.
    Mesh,
}

impl SceneName {
    /// Slices (and twice the rings) of each tessellated sphere: 16 slices and 8 rings, 224 triangles a sphere.
    pub const SEGMENTS: u32 = 16;

    /// True for the scenes of triangles.
    pub fn is_triangles(self) -> bool {
        matches!(self, SceneName::TessellatedSpheres | SceneName::RandomTriangles | SceneName::Mesh)
    }
}

impl Named for SceneName {
    const ALL: &'static [Self] = &[
        SceneName::Generated(SceneKind::RandomSpheres),
        SceneName::Generated(SceneKind::ClusteredSpheres),
        SceneName::SphereFile,
        SceneName::TessellatedSpheres,
        SceneName::RandomTriangles,
        SceneName::Mesh,
    ];
    fn name(self) -> &'static str {
        match self {
            SceneName::Generated(k) => k.name(),
            SceneName::SphereFile => "sphere-file",
            SceneName::TessellatedSpheres => "tessellated-spheres",
            SceneName::RandomTriangles => "random-triangles",
            SceneName::Mesh => "mesh",
        }
    }
}

/// The `mesh` setting: a data set name (`harness fetch NAME`) or a path to an `.obj` or `.ply` file or a folder of
/// `.ply` files (relative to where the harness runs).
#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct MeshSource(pub String);

impl fmt::Display for MeshSource {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

named_enum! {
    /// tinybvh's layouts (`tinybvh_layout`).
    TinyBvhLayout {
        /// `BVH`: the binary tree.
        Bvh = "bvh",
        /// `BVH4_CPU`: 4-wide nodes (SSE).
        Bvh4Cpu = "bvh4-cpu",
        /// `BVH8_CPU`: 8-wide nodes (AVX2).
        Bvh8Cpu = "bvh8-cpu",
    }
}

named_enum! {
    /// tinybvh's builders (`tinybvh_build`): `default` (`Build`, binned SAH) or `high` (`BuildHQ`, spatial splits).
    TinyBvhQuality { Default = "default", High = "high", }
}

named_enum! {
    /// Who builds the binary tree our wide BVH collapses (`tree_builder`): `ours`, tinybvh's `Build` / `BuildHQ`, or
    /// Embree's builder (`rtcBuildBVH`) medium / high.
    TreeBuilder {
        Ours = "ours",
        TinyBvh = "tinybvh",
        TinyBvhHigh = "tinybvh-high",
        Embree = "embree",
        EmbreeHigh = "embree-high",
    }
}

impl TreeBuilder {
    /// True when a peer library builds the tree (its split settings, not ours, shape it).
    pub fn is_peer(self) -> bool {
        self != TreeBuilder::Ours
    }

    /// True when Embree builds the tree (its library must load; its build threads are process-wide).
    pub fn is_embree(self) -> bool {
        matches!(self, TreeBuilder::Embree | TreeBuilder::EmbreeHigh)
    }
}

/// What a run computes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Workload {
    /// Full Whitted shading and PNG encoding.
    Render,
    /// One fixed ray set (primary, shadow or diffuse rays), the same for every backend.
    Rays(RayKind),
}

impl Named for Workload {
    const ALL: &'static [Self] = &[
        Workload::Render,
        Workload::Rays(RayKind::Primary),
        Workload::Rays(RayKind::Shadow),
        Workload::Rays(RayKind::Diffuse),
        Workload::Rays(RayKind::AmbientOcclusion),
    ];
    fn name(self) -> &'static str {
        match self {
            Workload::Render => "render",
            Workload::Rays(k) => k.name(),
        }
    }
}

impl Workload {
    /// The ray kind a workload is validated with (the render workload: its primary rays).
    pub fn validation_kind(self) -> RayKind {
        match self {
            Workload::Rays(k) => k,
            Workload::Render => RayKind::Primary,
        }
    }
}

/// A thread count as configs give it: a number, or every logical core of the machine that runs it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Threads {
    /// The machine's logical cores.
    All,
    /// Exactly this many.
    Count(u32),
}

impl Threads {
    /// The config word for [`Threads::All`].
    pub const ALL_WORD: &'static str = "all";

    /// [`Threads::All`] for the config word `all`.
    pub fn from_word(word: &str) -> Option<Threads> {
        (word == Threads::ALL_WORD).then_some(Threads::All)
    }

    /// The thread count on a machine with `cores` logical cores (the one place `"all"` is resolved).
    pub fn resolve(self, cores: usize) -> u32 {
        match self {
            Threads::All => cores as u32,
            Threads::Count(n) => n,
        }
    }

    /// The logical cores this process may use: what `all` means on this machine.
    pub fn cores_here() -> usize {
        std::thread::available_parallelism().map_or(1, |n| n.get())
    }

    /// The thread count on this machine ([`Threads::resolve`] with [`Threads::cores_here`]).
    pub fn here(self) -> u32 {
        match self {
            Threads::All => Threads::cores_here() as u32,
            Threads::Count(n) => n,
        }
    }
}

impl fmt::Display for Threads {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Threads::All => f.write_str(Threads::ALL_WORD),
            Threads::Count(n) => write!(f, "{n}"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn round_trip<T: Named>() {
        for &c in T::ALL {
            assert_eq!(T::from_name(c.name()), Some(c));
        }
        let mut names: Vec<_> = T::ALL.iter().map(|c| c.name()).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), T::ALL.len(), "names are distinct");
    }

    #[test]
    fn names_round_trip_and_are_distinct() {
        round_trip::<Accel>();
        round_trip::<SceneName>();
        round_trip::<Workload>();
        round_trip::<Split>();
        round_trip::<Traversal>();
        round_trip::<StrategyKind>();
        round_trip::<PeerKind>();
        round_trip::<ObvhsQuality>();
        round_trip::<EmbreeQuality>();
        round_trip::<EmbreeIsa>();
        round_trip::<Kernel>();
        round_trip::<ChildOrdering>();
        round_trip::<AnyHitOrdering>();
        round_trip::<Packet>();
        round_trip::<TriangleTest>();
        round_trip::<View>();
        round_trip::<TinyBvhLayout>();
        round_trip::<TinyBvhQuality>();
        assert_eq!(Accel::ALL.len(), AccelKind::ALL.len() + PeerKind::ALL.len());
        assert!(PeerKind::from_name("embree4").is_none());
    }

    #[test]
    fn packets_trace_the_tracers_batch_sizes() {
        let rays: Vec<u32> = Packet::ALL.iter().map(|p| p.rays()).collect();
        assert_eq!(rays, WideParams::PACKETS);
        assert!(Packet::ALL.iter().all(|&p| Packet::of_rays(p.rays()) == Some(p)));
        assert_eq!(Packet::of_rays(4), None);
    }
}
