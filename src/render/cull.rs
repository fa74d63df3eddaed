//! Which faces a draw may cull: the inside of a closed surface the eye cannot reach. Shared by
//! the shading pass, the shadow pass and the roofline's yardsticks.

use super::gpu_scene::LevelRange;
use super::plan::Plan;
use super::target::DepthConvention;
use crate::mesh::Enclosure;
use ash::vk;
use glam::{Mat4, Vec3};

/// The faces of a level of detail (its `enclosure`, its vertices' `bounds`) that no ray from
/// the eye reaches through `view_proj` (world -> clip, depth running as `convention` says), to
/// cull: the inner side of a surface that encloses a volume, when the whole of it lies beyond
/// the near plane (one the near plane cuts shows its inside); NONE for an open surface. On
/// screen a face is front (counter-clockwise, with the viewport's positive height) when its
/// winding's normal points towards the eye in clip space, which the sign of det(view_proj) (the
/// sign of the map's Jacobian wherever w > 0) and the depth's direction decide.
pub fn hidden_faces(
    enclosure: Enclosure,
    bounds: (Vec3, Vec3),
    view_proj: Mat4,
    convention: DepthConvention,
) -> vk::CullModeFlags {
    let outward = match enclosure {
        Enclosure::Open => return vk::CullModeFlags::NONE,
        Enclosure::Outward => true,
        Enclosure::Inward => false,
    };
    let (lo, hi) = bounds;
    let beyond_near = (0..8).all(|k| {
        let corner = Vec3::new(
            if k & 1 == 0 { lo.x } else { hi.x },
            if k & 2 == 0 { lo.y } else { hi.y },
            if k & 4 == 0 { lo.z } else { hi.z },
        );
        let clip = view_proj * corner.extend(1.0);
        // Vulkan's clip volume runs 0 <= z <= w; the near plane is z = 0, or z = w reversed.
        clip.w > 0.0
            && match convention {
                DepthConvention::Standard => clip.z > 0.0,
                DepthConvention::Reversed => clip.z < clip.w,
            }
    });
    let det = view_proj.determinant();
    if !beyond_near || !det.is_finite() || det == 0.0 {
        return vk::CullModeFlags::NONE;
    }
    let front_visible = (det > 0.0) == (convention == DepthConvention::Standard);
    if front_visible == outward { vk::CullModeFlags::BACK } else { vk::CullModeFlags::FRONT }
}

/// The faces to cull when drawing `level` through `view_proj`: its `hidden_faces` where `plan`
/// culls them (`Plan::cull_hidden_faces`), else none.
pub fn culled_faces(
    plan: &Plan,
    level: &LevelRange,
    view_proj: Mat4,
    convention: DepthConvention,
) -> vk::CullModeFlags {
    if plan.cull_hidden_faces {
        hidden_faces(level.enclosure, level.bounds, view_proj, convention)
    } else {
        vk::CullModeFlags::NONE
    }
}

