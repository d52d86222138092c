//! tinybvh through the harness's own shim (bindings in [`crate::peers::tinybvh`]): triangle scenes only, its
//! layout and builder from `tinybvh_layout` and `tinybvh_build`, traversed by the best ISA variant this CPU runs.

use schema::{Accel, PeerKind, Settings, TinyBvhLayout, TinyBvhQuality};

use super::{Backend, Built, Geometry, Setup, Unavailable};
use crate::error::Error;
use crate::peers::{TinyBvh, TinyBvhError, TinyIsa, TinyLayout, TinyQuality};

/// tinybvh, built into the harness.
pub struct TinyBvhBackend;

/// The peer's layout of `settings`.
fn layout(settings: &Settings) -> TinyLayout {
    match settings.tinybvh_layout.unwrap_or(TinyBvhLayout::Bvh) {
        TinyBvhLayout::Bvh => TinyLayout::Bvh,
        TinyBvhLayout::Bvh4Cpu => TinyLayout::Bvh4Cpu,
        TinyBvhLayout::Bvh8Cpu => TinyLayout::Bvh8Cpu,
    }
}

/// The peer's builder of `settings`.
fn quality(settings: &Settings) -> TinyQuality {
    match settings.tinybvh_build.unwrap_or(TinyBvhQuality::Default) {
        TinyBvhQuality::Default => TinyQuality::Default,
        TinyBvhQuality::High => TinyQuality::High,
    }
}

impl Backend for TinyBvhBackend {
    fn name(&self) -> &'static str {
        "tinybvh"
    }

    fn runs(&self, accel: Accel) -> bool {
        accel == Accel::Peer(PeerKind::TinyBvh)
    }

    fn here(&self) -> Result<String, Unavailable> {
        match TinyIsa::best() {
            Some(isa) => Ok(format!("built in (tinybvh 1.6.8 through our shim, {})", isa.name())),
            None => Err(Unavailable {
                reason: TinyBvhError::Unavailable("no variant of the shim runs on this CPU".into()).to_string(),
                installable: false,
            }),
        }
    }

    /// A wide layout runs only where a variant with it runs.
    fn available(&self, settings: &Settings) -> Result<(), Unavailable> {
        let isa = TinyIsa::best().ok_or_else(|| self.here().expect_err("no ISA variant runs"))?;
        let layout = layout(settings);
        if isa.has(layout) {
            Ok(())
        } else {
            Err(Unavailable { reason: TinyBvhError::LayoutNeedsIsa(layout, isa).to_string(), installable: false })
        }
    }

    fn build(&self, settings: &Settings, geometry: &Geometry<'_>, setup: &Setup) -> Result<Built, Error> {
        let Geometry::Triangles(mesh) = *geometry else {
            return Err(Error::Run("tinybvh traces triangles only".into()));
        };
        let (layout, quality) = (layout(settings), quality(settings));
        let bvh = setup.install(|| TinyBvh::build(mesh, layout, quality)).map_err(|e| Error::Run(format!("{e}")))?;
        let info = format!("tinybvh 1.6.8 {} {:?} ({})", layout.name(), quality, bvh.kernel());
        Ok(Built::peer(bvh, info))
    }
}
