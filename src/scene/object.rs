//! One scene object as the renderer and the references take it: its world-space mesh, its
//! material resolved, its sample points and levels of detail (`build` prepares them).

use super::accuracy::Density;
use crate::mesh::Mesh;
use crate::optics::{Dipole, Material};
use crate::sampling::{self, SamplePoint};

/// An object's material, resolved.
#[derive(Clone, Debug)]
#[allow(clippy::large_enum_variant)] // one per object, never in a hot loop
pub enum ResolvedMaterial {
    /// A dipole-diffusion material with its three channels' dipoles in scene units.
    Translucent {
        /// Coefficients in 1/mm (preset or custom, `eta` overridden where the scene gives one).
        material: Material,
        /// The R, G, B dipoles, in scene units (`material` scaled by `mm_per_unit`).
        dipoles: [Dipole; 3],
        /// Millimetres per scene unit.
        mm_per_unit: f64,
        /// GGX roughness of the dielectric specular lobe (0 to 1).
        roughness: f32,
        /// Which model each channel takes (`material.model`).
        model: super::ScatteringModel,
    },
    /// Lambertian with a GGX specular lobe.
    Opaque {
        /// Diffuse albedo per channel (0 to 1).
        albedo: [f32; 3],
        /// GGX roughness of the specular lobe (0 to 1).
        roughness: f32,
    },
}

/// One scene object ready to upload: world-space mesh, resolved material and sample points.
#[derive(Clone, Debug)]
pub struct PreparedObject {
    /// For messages: the mesh path or the built-in shape.
    pub name: String,
    /// World-space mesh.
    pub mesh: Mesh,
    /// The mesh as loaded, before its transform, where the samples are placed
    /// (`sampling::sample_in_frame`, so that the same object gets the same samples in any units
    /// and at any place); `None` where the transform is the identity.
    pub frame: Option<std::sync::Arc<Mesh>>,
    /// What it is made of.
    pub material: ResolvedMaterial,
    /// Whether it is drawn into the shadow maps (`casts_shadow` in the scene).
    pub casts_shadow: bool,
    /// World-space sample points with area weights (translucent objects only).
    pub samples: Vec<SamplePoint>,
    /// How many samples it got and the error predicted for them (translucent objects only).
    pub density: Option<Density>,
    /// Its levels of detail, finest (the mesh itself) first; only the mesh itself when
    /// `render.level_of_detail` is off or the object's shading rests on per-vertex data the
    /// simplifier cannot see (`lod_allowed`).
    pub levels: Vec<crate::mesh::LodLevel>,
    /// The texture gather's atlas of its mesh, whose texels are then its samples (translucent
    /// objects of a scene with `render.gather = "texture"` only).
    pub atlas: Option<std::sync::Arc<crate::mesh::atlas::Atlas>>,
    /// Its transport kernel where `material.model = "transport"` and the caller attached one
    /// (`reference::transport_cache`); until then the object takes the dipole.
    pub transport: Option<std::sync::Arc<crate::optics::transport::TransportKernel>>,
    /// Why a kernel it had was dropped (it takes the dipole until one is attached again).
    pub kernel_dropped: Option<KernelDropped>,
    /// Which model each channel takes and why (translucent objects only; `material.model`).
    pub model: Option<super::model_choice::ModelChoice>,
}

/// Why an object's transport kernel no longer holds, so that it was dropped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum KernelDropped {
    /// Its material changed (`SceneEdit::Material`): the kernel is the old medium's.
    MaterialEdited,
    /// It was moved by more than a rotation and translation (`SceneEdit::Transform`): a scale
    /// changes its size against the medium's free paths.
    Scaled,
}

impl std::fmt::Display for KernelDropped {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            KernelDropped::MaterialEdited => "its material was edited, and the kernel is the old medium's",
            KernelDropped::Scaled => "it was scaled, and the kernel is for its old size",
        })
    }
}

impl PreparedObject {
    /// Per channel, whether it takes single scattering between points (`material.model`);
    /// none for an opaque object.
    pub fn single_channels(&self) -> [bool; 3] {
        match &self.material {
            ResolvedMaterial::Translucent { dipoles, model, .. } => {
                model.single_channels(dipoles.map(|d| d.alpha_prime))
            }
            ResolvedMaterial::Opaque { .. } => [false; 3],
        }
    }

    /// Whether its material asks for the transport kernel: `material.model = "transport"`, or
    /// `"auto"` where the dipole's predicted error is over `render.max_error`
    /// (`scene::model_choice`).
    pub fn wants_transport(&self) -> bool {
        matches!(&self.material, ResolvedMaterial::Translucent { model: super::ScatteringModel::Transport, .. })
            || self.model.as_ref().is_some_and(super::model_choice::ModelChoice::kernel)
    }

    /// Chooses each channel's model anew (`scene::model_choice`) for `render.max_error`
    /// `target`: after sampling, and after a material edit.
    pub fn choose_model(&mut self, target: f64) {
        use super::model_choice::{ModelChoice, object_size};
        self.model = match &self.material {
            ResolvedMaterial::Translucent { dipoles, model, .. } => {
                let curvature_radius = self.density.as_ref().map_or(f64::INFINITY, |d| d.facts.curvature_radius);
                let size = object_size(&self.mesh, curvature_radius);
                Some(ModelChoice::choose(*model, dipoles, size, target))
            }
            ResolvedMaterial::Opaque { .. } => None,
        };
    }

    /// The hierarchy over its samples for the hierarchical gather (built on each call; the
    /// renderer and the f64 reference each build it once, identically). Its reach is the widest
    /// channel's near-blend radius.
    pub fn sample_tree(&self) -> sampling::SampleTree {
        let positions: Vec<glam::DVec3> = self.samples.iter().map(|s| s.position.as_dvec3()).collect();
        let areas: Vec<f64> = self.samples.iter().map(|s| s.area).collect();
        let widest = self.near_blend_radii().into_iter().fold(crate::optics::kernel::NEAR_BLEND_RADIUS, f64::max);
        sampling::SampleTree::new(&positions, &areas, widest)
    }

    /// Per channel, the near-field blend's radius in units of `sqrt(dA)` for its samples
    /// (`optics::kernel::near_blend_radii` at their mean area); the least radius for an opaque
    /// object or one without samples.
    pub fn near_blend_radii(&self) -> [f64; 3] {
        use crate::optics::kernel;
        match &self.material {
            ResolvedMaterial::Translucent { dipoles, .. } if !self.samples.is_empty() => {
                let mean_area = self.samples.iter().map(|s| s.area).sum::<f64>() / self.samples.len() as f64;
                kernel::near_blend_radii(dipoles, mean_area)
            }
            _ => [kernel::NEAR_BLEND_RADIUS; 3],
        }
    }

    /// The hierarchical gather's items for each receiver, in `groups.order` (receivers at
    /// `positions`), at accuracy `epsilon`: each receiver's own cut (`sampling::SampleTree::cut`
    /// about its point, nodes dropped by `optics::kernel::negligible_cluster`); empty lists for
    /// an opaque object. Its own, not its group's: a group's cut lists one by one every sample
    /// within reach of any of its receivers, which on a coarse level of detail is three times
    /// what one receiver needs (docs/STUDY.md, "What a group's list costs").
    pub fn gather_cuts(
        &self,
        tree: &sampling::SampleTree,
        groups: &sampling::ReceiverGroups,
        positions: &[glam::DVec3],
        epsilon: f64,
    ) -> sampling::Cuts {
        let ResolvedMaterial::Translucent { dipoles, .. } = &self.material else {
            return sampling::Cuts::build(groups.order.len(), |_, _| {});
        };
        let negligible =
            |n: &sampling::TreeNode, dist: f64| crate::optics::kernel::negligible_cluster(dipoles, n.area as f64, dist);
        sampling::Cuts::build(groups.order.len(), |k, items| {
            let at = positions[groups.order[k] as usize].as_vec3().to_array();
            tree.cut_into((at, 0.0), epsilon, negligible, items)
        })
    }

    /// Make the texels of an atlas of its mesh at `resolution` its samples (the texture
    /// gather's; `mesh::atlas`), its density judged for their count.
    pub fn place_texels(&mut self, resolution: u32) -> Result<(), crate::mesh::atlas::AtlasError> {
        let atlas = crate::mesh::atlas::Atlas::new(&self.mesh, resolution)?;
        self.samples = atlas.texels.iter().map(texel_sample).collect();
        if let ResolvedMaterial::Translucent { dipoles, .. } = &self.material {
            self.density = self.density.as_ref().map(|d| d.given(dipoles, self.samples.len()));
        }
        self.atlas = Some(std::sync::Arc::new(atlas));
        Ok(())
    }

    /// The texture gather's local window half-width in texels (`mesh::atlas::window_radius`
    /// for its atlas and its widest channel's profile); `None` without an atlas.
    pub fn window_radius(&self) -> Option<u32> {
        let (Some(atlas), ResolvedMaterial::Translucent { dipoles, .. }) = (&self.atlas, &self.material) else {
            return None;
        };
        let widest = dipoles.iter().map(|d| d.profile_radius()).fold(0.0, f64::max);
        Some(crate::mesh::atlas::window_radius(atlas.scale, widest))
    }

    /// Its vertices as the hierarchical gather groups them (`sampling::ReceiverGroups`).
    pub fn receiver_groups(&self) -> sampling::ReceiverGroups {
        let positions: Vec<glam::DVec3> = self.mesh.positions().iter().map(|p| p.as_dvec3()).collect();
        sampling::ReceiverGroups::new(&positions)
    }
}

/// A texel of the texture gather's atlas as a sample point (`mesh::atlas`: it carries the area
/// of the surface it stands for).
fn texel_sample(t: &crate::mesh::atlas::Texel) -> SamplePoint {
    SamplePoint {
        position: t.position,
        normal: t.normal,
        triangle: t.triangle,
        barycentric: t.barycentric.map(|b| b as f32),
        area: t.area,
    }
}
