//! glTF materials as scene materials. A material with `KHR_materials_volume` (not thin-walled)
//! or `KHR_materials_diffuse_transmission` is a translucent medium: the volume's attenuation
//! gives the reduced extinction per channel, `sigma_t' = -ln(attenuationColor) /
//! attenuationDistance`, and the base colour the reduced albedo `alpha'` whose dipole reflects
//! that colour (`R_d,total` inverted, `optics::albedo`); `KHR_materials_ior` gives `eta`. Every
//! other material is opaque: its base colour the albedo. Roughness is the metallic-roughness
//! roughness factor, which is GGX's perceptual roughness as the scene's is. A material the
//! overrides name is theirs.

use super::{GltfOverrides, GltfPart, GltfSceneProblem, MM_PER_GLTF_UNIT};
use crate::scene::format::{MaterialSpec, ScatteringModel};

/// The `KHR_materials_diffuse_transmission` extension's name, read from the material's raw
/// extensions (the gltf crate 1.4 has no type for it).
pub const DIFFUSE_TRANSMISSION: &str = "KHR_materials_diffuse_transmission";

/// glTF's index of refraction where `KHR_materials_ior` gives none.
const DEFAULT_IOR: f32 = 1.5;

/// Every material of a file mapped, and glTF's default material.
pub(super) struct Materials {
    by_index: Vec<(MaterialSpec, GltfPart)>,
    default: (MaterialSpec, GltfPart),
}

impl Materials {
    /// The material of index `index` (`None`: the default) and its part of the file.
    pub fn get(&self, index: Option<usize>) -> (MaterialSpec, GltfPart) {
        index.and_then(|i| self.by_index.get(i)).unwrap_or(&self.default).clone()
    }
}

/// Every material of `document` mapped, `overrides` applied by name; an override naming no
/// material of the file is refused.
pub(super) fn materials(
    document: &::gltf::Gltf,
    overrides: &GltfOverrides,
) -> Result<Materials, Box<GltfSceneProblem>> {
    let names: Vec<String> = document.materials().filter_map(|m| m.name().map(str::to_string)).collect();
    if let Some(name) = overrides.material.keys().find(|n| !names.contains(n)) {
        return Err(Box::new(GltfSceneProblem::NoSuchMaterial { name: name.clone(), names }));
    }
    let by_index = document
        .materials()
        .map(|m| {
            let part = GltfPart::Material { index: m.index(), name: m.name().map(str::to_string) };
            let spec = match m.name().and_then(|n| overrides.material.get(n)) {
                Some(spec) => spec.clone(),
                None => spec(&m, &part)?,
            };
            Ok((spec, part))
        })
        .collect::<Result<_, Box<GltfSceneProblem>>>()?;
    let part = GltfPart::Material { index: None, name: None };
    let default = (MaterialSpec::Opaque { albedo: [1.0; 3], roughness: 1.0 }, part);
    Ok(Materials { by_index, default })
}

/// One material mapped: translucent where it has a volume or diffuse transmission, else opaque.
fn spec(material: &::gltf::Material, part: &GltfPart) -> Result<MaterialSpec, Box<GltfSceneProblem>> {
    let volume = material.volume().filter(|v| v.thickness_factor() > 0.0);
    let diffuse_transmission = material.extension_value(DIFFUSE_TRANSMISSION).is_some();
    match (volume, diffuse_transmission) {
        (Some(volume), _) => medium(material, &volume, part),
        (None, true) => Err(Box::new(GltfSceneProblem::NoVolume { material: part.clone() })),
        (None, false) => Ok(opaque(material)),
    }
}

/// Lambertian with the base colour's RGB as albedo (alpha and textures not read).
fn opaque(material: &::gltf::Material) -> MaterialSpec {
    let pbr = material.pbr_metallic_roughness();
    let [r, g, b, _] = pbr.base_color_factor();
    MaterialSpec::Opaque { albedo: [r, g, b], roughness: pbr.roughness_factor() }
}

/// The translucent medium of a material with a volume: per channel `sigma_t'` from the
/// attenuation, `alpha'` from the base colour, in 1/mm with [`MM_PER_GLTF_UNIT`].
fn medium(
    material: &::gltf::Material,
    volume: &::gltf::material::Volume,
    part: &GltfPart,
) -> Result<MaterialSpec, Box<GltfSceneProblem>> {
    let eta = f64::from(material.ior().unwrap_or(DEFAULT_IOR));
    let pbr = material.pbr_metallic_roughness();
    let base = pbr.base_color_factor();
    let (color, distance) = (volume.attenuation_color(), volume.attenuation_distance());
    let mut sigma_a = [0.0; 3];
    let mut sigma_s_prime = [0.0; 3];
    for c in 0..3 {
        let per_unit = -f64::from(color[c]).ln() / f64::from(distance);
        if !(per_unit.is_finite() && per_unit > 0.0) {
            return Err(Box::new(GltfSceneProblem::NoExtinction {
                material: part.clone(),
                channel: c,
                color: color[c],
                distance,
            }));
        }
        let medium = |source| Box::new(GltfSceneProblem::Medium { material: part.clone(), source });
        let alpha = crate::optics::albedo::reduced_albedo(f64::from(base[c]), eta).map_err(medium)?;
        let sigma_t = per_unit / MM_PER_GLTF_UNIT;
        sigma_s_prime[c] = alpha * sigma_t;
        sigma_a[c] = (1.0 - alpha) * sigma_t;
    }
    Ok(MaterialSpec::Translucent {
        preset: None,
        sigma_a: Some(sigma_a),
        sigma_s_prime: Some(sigma_s_prime),
        eta: Some(eta),
        mm_per_unit: MM_PER_GLTF_UNIT,
        roughness: pbr.roughness_factor(),
        model: ScatteringModel::default(),
    })
}
