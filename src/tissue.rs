//! The calibrated tissues shipped in `assets/`: the mass-spring parameters of the preset objects
//! `A` and `B` for each lattice topology.

use anyhow::Context as _;

use crate::material::Material;
use crate::msm::{MsmParams, Topology};

/// The calibrated tissue parameters shipped in `assets/` for object `A` or `B`: the shear-spring
/// model (the viewer's default), the hex-element model or the paper's axis-spring model, all calibrated by this program
/// (hybrid GA+SA, seed 1, static cost; see each file's `note`).
pub fn tissue_params(material: &Material, topology: Topology) -> anyhow::Result<MsmParams> {
    let is_preset = Material::preset(&material.name)
        .is_some_and(|p| p.constants == material.constants && p.density == material.density);
    if !is_preset {
        anyhow::bail!(
            "no calibrated tissue is shipped for material {:?} (only the presets A and B); calibrate one",
            material.name
        );
    }
    let text = match (material.name.as_str(), topology) {
        ("A", Topology::Shear) => include_str!("../assets/tissue_A_shear.json"),
        ("B", Topology::Shear) => include_str!("../assets/tissue_B_shear.json"),
        ("A", Topology::Axis) => include_str!("../assets/tissue_A_axis.json"),
        ("B", Topology::Axis) => include_str!("../assets/tissue_B_axis.json"),
        ("A", Topology::Hex) => include_str!("../assets/tissue_A_hex.json"),
        ("B", Topology::Hex) => include_str!("../assets/tissue_B_hex.json"),
        (other, _) => anyhow::bail!("no calibrated tissue is shipped for object {other:?}; calibrate one"),
    };
    #[derive(serde::Deserialize)]
    struct Shipped {
        params: MsmParams,
    }
    let shipped: Shipped = serde_json::from_str(text).context("assets: invalid tissue file")?;
    Ok(shipped.params)
}
