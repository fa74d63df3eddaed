//! Which model each channel of a translucent object takes, and why (`material.model`): the
//! dipole, single scattering between points, or the dipole scaled by the object's transport
//! kernel. `"auto"` weighs the dipole's predicted error against the light
//! (`optics::model_error`) against the scene's `render.max_error`.

use super::ScatteringModel;
use crate::mesh::Mesh;
use crate::optics::Dipole;
use crate::optics::model_error::{self, DipoleError, ModelFacts};

/// The model a channel takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ChannelModel {
    /// The dipole sum (seed Eq. 11).
    Dipole,
    /// Single scattering between points (`optics::beam_single`).
    Single,
    /// The dipole scaled per patch by the object's transport kernel (`optics::transport`).
    Kernel,
}

/// Why a channel takes its model.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
#[serde(tag = "why", rename_all = "snake_case")]
pub enum ModelReason {
    /// `material.model` names it.
    Named,
    /// Its reduced albedo is under `optics::beam_single::ALBEDO_BELOW`: most light leaves after
    /// one or two scatterings along the refracted beam, which single scattering follows.
    LowAlbedo {
        /// The channel's reduced albedo.
        alpha_prime: f64,
    },
    /// `"auto"`: the dipole's predicted error is within `render.max_error` in every channel the
    /// dipole would take.
    DipoleWithinTarget,
    /// `"auto"`: the dipole's predicted error is over `render.max_error` in some channel, so the
    /// object's kernel is walked, and it serves every channel the dipole would have taken (a
    /// kernel costs the same for one channel as for three).
    DipoleOverTarget,
    /// `"auto"`: the dipole's predicted error is over `render.max_error`, but the mesh is not
    /// closed, and a kernel is walked only inside a closed surface.
    OpenMesh,
}

/// One channel's choice and the prediction behind it.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ChannelChoice {
    /// The model taken.
    pub takes: ChannelModel,
    /// Why.
    pub reason: ModelReason,
    /// What the dipole's error depends on here.
    pub facts: ModelFacts,
    /// The dipole's predicted error against the light, with its terms.
    pub dipole: DipoleError,
    /// The predicted error of the model taken against the light, per lit vertex; `None` for
    /// single scattering, whose error has no fitted model yet.
    pub predicted: Option<f64>,
}

/// An object's models, per channel.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ModelChoice {
    /// The object's size `L` in scene units ([`object_size`]).
    pub size: f64,
    /// `render.max_error` weighed.
    pub target: f64,
    /// Per channel (R, G, B).
    pub channels: [ChannelChoice; 3],
}

impl ModelChoice {
    /// The choice of `model` for an object of `size` with channels `dipoles`, against `target`;
    /// `closed` says whether its mesh encloses a volume (a kernel can be walked in it).
    pub fn choose(
        model: ScatteringModel,
        dipoles: &[Dipole; 3],
        (size, closed): (f64, bool),
        target: f64,
    ) -> ModelChoice {
        let single = model.single_channels(dipoles.map(|d| d.alpha_prime));
        let facts = dipoles.map(|d| ModelFacts::new(d.alpha_prime, d.mean_free_path(), size));
        let dipole = facts.map(|f| model_error::dipole_error(&f));
        // NaN counts as over.
        let over = (0..3).any(|c| !single[c] && (dipole[c].error.is_nan() || dipole[c].error > target));
        let (rest, why) = match model {
            ScatteringModel::Dipole | ScatteringModel::Single => (ChannelModel::Dipole, ModelReason::Named),
            ScatteringModel::Transport => (ChannelModel::Kernel, ModelReason::Named),
            ScatteringModel::Auto if over && !closed => (ChannelModel::Dipole, ModelReason::OpenMesh),
            ScatteringModel::Auto if over => (ChannelModel::Kernel, ModelReason::DipoleOverTarget),
            ScatteringModel::Auto => (ChannelModel::Dipole, ModelReason::DipoleWithinTarget),
        };
        let channels = [0, 1, 2].map(|c| {
            let (takes, reason) = match (single[c], model) {
                (true, ScatteringModel::Single) => (ChannelModel::Single, ModelReason::Named),
                (true, _) => (ChannelModel::Single, ModelReason::LowAlbedo { alpha_prime: dipoles[c].alpha_prime }),
                (false, _) => (rest, why),
            };
            let predicted = match takes {
                ChannelModel::Dipole => Some(dipole[c].error),
                ChannelModel::Kernel => Some(model_error::kernel_error(dipole[c].error)),
                ChannelModel::Single => None,
            };
            ChannelChoice { takes, reason, facts: facts[c], dipole: dipole[c], predicted }
        });
        ModelChoice { size, target, channels }
    }

    /// Per channel, the predicted total error against the light where the discretisation's is
    /// `discretisation`: the two in quadrature, as independent errors add (`None` where the
    /// model's own is not predicted).
    pub fn total(&self, discretisation: [f64; 3]) -> [Option<f64>; 3] {
        [0, 1, 2].map(|c| self.channels[c].predicted.map(|m| m.hypot(discretisation[c])))
    }

    /// Whether any channel takes the transport kernel.
    pub fn kernel(&self) -> bool {
        self.channels.iter().any(|c| c.takes == ChannelModel::Kernel)
    }
}

impl std::fmt::Display for ModelChoice {
    /// `R kernel (dipole predicted 29% against the light, kernel 12%), G ..., size 10 mm`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let pct = |x: f64| format!("{:.3}%", 100.0 * x);
        for (c, ch) in self.channels.iter().enumerate() {
            let name = ["R", "G", "B"][c];
            let takes = match ch.takes {
                ChannelModel::Dipole => "dipole",
                ChannelModel::Single => "single scattering",
                ChannelModel::Kernel => "transport kernel",
            };
            let sep = if c > 0 { "; " } else { "" };
            write!(f, "{sep}{name} {takes} (dipole predicted {} against the light", pct(ch.dipole.error))?;
            match (ch.takes, ch.predicted) {
                (ChannelModel::Kernel, Some(p)) => write!(f, ", kernel {})", pct(p))?,
                _ => write!(f, ")")?,
            }
        }
        write!(f, "; size {:.4} units, max_error {}", self.size, pct(self.target))
    }
}

/// An object's size `L` for the model error, and whether its mesh is closed: `3 V / A` of a
/// closed mesh (a sphere's radius), else `curvature_radius` (the RMS radius of its mean
/// curvature; infinite for a flat one).
pub fn object_size(mesh: &Mesh, curvature_radius: f64) -> (f64, bool) {
    if !mesh.report().is_closed_manifold() {
        return (curvature_radius, false);
    }
    let volume = crate::mesh::enclosure::signed_volume(mesh.positions(), mesh.triangles());
    let area = mesh.total_area();
    if area > 0.0 { (3.0 * volume.abs() / area, true) } else { (curvature_radius, true) }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::shapes;
    use crate::optics::Material;

    /// The choice for a sphere of `radius` metres of `preset` under `model` and `target`.
    fn sphere(preset: &str, radius: f32, model: ScatteringModel, target: f64) -> ModelChoice {
        let mesh = shapes::sphere(radius, 24).unwrap();
        let dipoles = Material::preset(preset).unwrap().dipoles(1000.0).unwrap();
        ModelChoice::choose(model, &dipoles, object_size(&mesh, f64::INFINITY), target)
    }

    #[test]
    fn a_sphere_is_sized_by_its_radius() {
        let (size, closed) = object_size(&shapes::sphere(0.01, 48).unwrap(), f64::INFINITY);
        assert!(closed && (size - 0.01).abs() < 2e-4, "{size}");
        let (flat, closed) = object_size(&shapes::plane(1.0, 4).unwrap(), f64::INFINITY);
        assert!(!closed && flat.is_infinite());
    }

    #[test]
    fn auto_walks_the_kernel_where_the_dipole_misses_the_target_and_not_where_it_meets_it() {
        let tight = sphere("marble", 0.01, ScatteringModel::Auto, 0.01);
        assert!(tight.kernel(), "{tight}");
        assert!(tight.channels.iter().all(|c| c.reason == ModelReason::DipoleOverTarget));
        let loose = sphere("marble", 0.01, ScatteringModel::Auto, 0.9);
        assert!(!loose.kernel(), "{loose}");
        assert!(loose.channels.iter().all(|c| c.reason == ModelReason::DipoleWithinTarget));
        // A 2 cm marble sphere: the study measured the dipole 27 to 31% off.
        for c in &tight.channels {
            assert!((0.15..0.4).contains(&c.dipole.error), "{tight}");
            assert!(c.predicted.unwrap() < c.dipole.error);
        }
    }

    #[test]
    fn auto_gives_ketchups_dark_channels_single_scattering_and_its_red_the_kernel() {
        let ketchup = sphere("ketchup", 0.01, ScatteringModel::Auto, 0.01);
        let takes = ketchup.channels.map(|c| c.takes);
        assert_eq!(takes, [ChannelModel::Kernel, ChannelModel::Single, ChannelModel::Single], "{ketchup}");
        assert!(matches!(ketchup.channels[1].reason, ModelReason::LowAlbedo { .. }));
    }

    #[test]
    fn named_models_are_taken_as_named_whatever_the_prediction() {
        let dipole = sphere("marble", 0.01, ScatteringModel::Dipole, 0.01);
        assert!(dipole.channels.iter().all(|c| c.takes == ChannelModel::Dipole && c.reason == ModelReason::Named));
        let kernel = sphere("marble", 0.01, ScatteringModel::Transport, 0.9);
        assert!(kernel.channels.iter().all(|c| c.takes == ChannelModel::Kernel && c.reason == ModelReason::Named));
    }

    #[test]
    fn an_open_mesh_keeps_the_dipole_with_its_reason() {
        let mesh = shapes::plane(0.02, 4).unwrap();
        let dipoles = Material::preset("marble").unwrap().dipoles(1000.0).unwrap();
        let choice = ModelChoice::choose(ScatteringModel::Auto, &dipoles, object_size(&mesh, 0.005), 0.01);
        assert!(!choice.kernel() && choice.channels.iter().all(|c| c.reason == ModelReason::OpenMesh), "{choice}");
    }
}
