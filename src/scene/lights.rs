//! Scene lights turned into GPU records, with shadow matrices, and the environment light
//! reduced to directional lights by median cut (Debevec 2006, "A median cut algorithm for light
//! probe sampling"): regions of equal energy on the equirectangular map, each replaced by one
//! directional light carrying the region's irradiance, each with its own shadow map. Together
//! they give the soft environment shadows of the seed paper's Figure 6. The GPU record of a
//! light (`render::records::LightGpu`) is packed from these typed values.

use super::format::Light;
use glam::camera::rh::{proj::vulkan, view::look_at_mat4};
use glam::{Mat4, Vec3};

/// An environment as an equirectangular grid of linear radiance (W/m^2/sr). Row 0 looks at
/// +y (up); column u covers azimuth phi = 2 pi (u + 0.5) / width, direction
/// (sin theta cos phi, cos theta, sin theta sin phi).
#[derive(Clone, Debug)]
pub struct Environment {
    /// Columns (texels of azimuth).
    pub width: usize,
    /// Rows (texels of polar angle, from +y down to -y).
    pub height: usize,
    /// Linear RGB radiance (W/m^2/sr), row by row from the top, `width * height` texels.
    pub radiance: Vec<Vec3>,
}

/// Why an environment map was refused; every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum EnvironmentError {
    // The image error is the source (shown by `{:#}` and error reporters), not repeated here.
    /// The file could not be opened or decoded.
    #[error("cannot read environment map {}", path.display())]
    Read {
        /// The map's file.
        path: std::path::PathBuf,
        /// The decoder's error.
        source: image::ImageError,
    },
    /// The map is less than 2 texels wide or high.
    #[error("environment map {} is only {width}x{height}", path.display())]
    TooSmall {
        /// The map's file.
        path: std::path::PathBuf,
        /// Its width in texels.
        width: usize,
        /// Its height in texels.
        height: usize,
    },
    /// The map is wider or higher than `MAX_ENVIRONMENT_SIDE` or has more than the allowed
    /// number of texels (`MAX_ENVIRONMENT_TEXELS` when loaded from a file): found from the
    /// header, before any texel is decoded.
    #[error(
        "environment map {} is {width}x{height}, above the limit of {limit} texels and \
         {side} texels a side (an 8192x4096 map fits; downscale it)",
        path.display(), side = MAX_ENVIRONMENT_SIDE
    )]
    TooLarge {
        /// The map's file.
        path: std::path::PathBuf,
        /// Its width in texels, from the header.
        width: usize,
        /// Its height in texels, from the header.
        height: usize,
        /// The limit it exceeds.
        limit: usize,
    },
    /// A texel is negative, infinite or NaN.
    #[error("environment map {}: texel ({x}, {y}) is {value:?}, negative or not finite", path.display())]
    BadTexel {
        /// The map's file.
        path: std::path::PathBuf,
        /// The texel's column.
        x: usize,
        /// The texel's row.
        y: usize,
        /// Its radiance.
        value: [f32; 3],
    },
    /// A texel is brighter than `MAX_RADIANCE`: sums over the map would overflow f32.
    #[error(
        "environment map {}: texel ({x}, {y}) is {value:?}, above the limit of {limit:e} \
         (sums over the map would overflow)",
        path.display(), limit = MAX_RADIANCE
    )]
    TooBright {
        /// The map's file.
        path: std::path::PathBuf,
        /// The texel's column.
        x: usize,
        /// The texel's row.
        y: usize,
        /// Its radiance.
        value: [f32; 3],
    },
}

/// The largest radiance an environment map may hold: the median cut sums radiance times solid
/// angle over the whole map (at most 4 pi sr) in f32, so larger texels (an RGBE exponent near
/// 255 gives 1.7e38) would overflow to infinite lights.
pub const MAX_RADIANCE: f32 = 1e30;

/// The most texels an environment map may have: an 8K equirectangular map (8192x4096). The
/// per-vertex cache and the median cut walk the whole map, and a header can claim any size.
pub const MAX_ENVIRONMENT_TEXELS: usize = 8192 * 4096;

/// The widest or highest an environment map may be. An equirectangular map is twice as wide as
/// high; a header claiming millions of texels in one row is refused before decoding (the EXR
/// decoder took 10 s on 881 bytes claiming 7733242x4).
pub const MAX_ENVIRONMENT_SIDE: usize = 16384;

impl Environment {
    /// The built-in sky: a blue zenith fading to a bright horizon; nothing from below the
    /// horizon (light bounced off the ground is not simulated, and would reach objects through
    /// floors that cast no shadow).
    pub fn procedural_sky(width: usize, height: usize) -> Environment {
        let zenith = Vec3::new(0.30, 0.45, 0.85);
        let horizon = Vec3::new(0.85, 0.88, 0.95);
        let ground = Vec3::ZERO;
        let mut radiance = Vec::with_capacity(width * height);
        for y in 0..height {
            for x in 0..width {
                let d = Self::direction_of(width, height, x as f32 + 0.5, y as f32 + 0.5);
                radiance.push(if d.y >= 0.0 { horizon.lerp(zenith, d.y.sqrt()) } else { ground });
            }
        }
        Environment { width, height, radiance }
    }

    /// Load an equirectangular .hdr or .exr map (through the `image` crate). The format comes
    /// from the extension, or from the content when the extension names none.
    pub fn load(path: &std::path::Path) -> Result<Environment, EnvironmentError> {
        let read = |source| EnvironmentError::Read { path: path.to_path_buf(), source };
        let bytes = std::fs::read(path).map_err(|e| read(image::ImageError::IoError(e)))?;
        Self::decode(&bytes, image::ImageFormat::from_path(path).ok(), path, MAX_ENVIRONMENT_TEXELS)
    }

    /// Decode an equirectangular .hdr or .exr map already in memory, the format guessed from
    /// its content; `name` names it in errors.
    pub fn from_bytes(bytes: &[u8], name: impl AsRef<std::path::Path>) -> Result<Environment, EnvironmentError> {
        Self::decode(bytes, None, name.as_ref(), MAX_ENVIRONMENT_TEXELS)
    }

    /// `from_bytes` with a lower texel limit than `MAX_ENVIRONMENT_TEXELS`: a caller that
    /// decodes untrusted maps in bulk (the fuzzer) keeps each one cheap.
    pub fn from_bytes_within(
        bytes: &[u8],
        name: impl AsRef<std::path::Path>,
        max_texels: usize,
    ) -> Result<Environment, EnvironmentError> {
        Self::decode(bytes, None, name.as_ref(), max_texels.min(MAX_ENVIRONMENT_TEXELS))
    }

    fn decode(
        bytes: &[u8],
        format: Option<image::ImageFormat>,
        path: &std::path::Path,
        max_texels: usize,
    ) -> Result<Environment, EnvironmentError> {
        let read = |source| EnvironmentError::Read { path: path.to_path_buf(), source };
        let reader = || -> Result<_, EnvironmentError> {
            let mut reader = image::ImageReader::new(std::io::Cursor::new(bytes));
            match format {
                Some(format) => reader.set_format(format),
                None => reader = reader.with_guessed_format().map_err(|e| read(image::ImageError::IoError(e)))?,
            }
            Ok(reader)
        };
        // The header's size first: decoding a map that claims millions of texels takes seconds
        // even when the file holds a few bytes of them.
        let (width, height) = reader()?.into_dimensions().map_err(read)?;
        let (width, height) = (width as usize, height as usize);
        if width.saturating_mul(height) > max_texels || width.max(height) > MAX_ENVIRONMENT_SIDE {
            return Err(EnvironmentError::TooLarge { path: path.to_path_buf(), width, height, limit: max_texels });
        }
        let img = reader()?.decode().map_err(read)?;
        let rgb = img.to_rgb32f();
        let (width, height) = (rgb.width() as usize, rgb.height() as usize);
        if width < 2 || height < 2 {
            return Err(EnvironmentError::TooSmall { path: path.to_path_buf(), width, height });
        }
        let mut radiance = Vec::with_capacity(width * height);
        for (x, y, p) in rgb.enumerate_pixels() {
            let v = Vec3::new(p[0], p[1], p[2]);
            let (x, y, path, value) = (x as usize, y as usize, path.to_path_buf(), v.to_array());
            if !v.is_finite() || v.min_element() < 0.0 {
                return Err(EnvironmentError::BadTexel { path, x, y, value });
            }
            if v.max_element() > MAX_RADIANCE {
                return Err(EnvironmentError::TooBright { path, x, y, value });
            }
            radiance.push(v);
        }
        Ok(Environment { width, height, radiance })
    }

    fn direction_of(width: usize, height: usize, u: f32, v: f32) -> Vec3 {
        let theta = std::f32::consts::PI * v / height as f32;
        let phi = 2.0 * std::f32::consts::PI * u / width as f32;
        Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin())
    }

    /// Solid angle of one texel in row `y`.
    fn texel_solid_angle(&self, y: usize) -> f32 {
        let theta = std::f32::consts::PI * (y as f32 + 0.5) / self.height as f32;
        (2.0 * std::f32::consts::PI / self.width as f32) * (std::f32::consts::PI / self.height as f32) * theta.sin()
    }

    /// Irradiance on a surface with normal `n`, by direct integration over the map (reference).
    pub fn irradiance(&self, n: Vec3) -> Vec3 {
        let mut e = Vec3::ZERO;
        for y in 0..self.height {
            let dw = self.texel_solid_angle(y);
            for x in 0..self.width {
                let d = Self::direction_of(self.width, self.height, x as f32 + 0.5, y as f32 + 0.5);
                e += self.radiance[y * self.width + x] * dw * n.dot(d).max(0.0);
            }
        }
        e
    }

    /// Up to `k` directional lights (unit direction towards the light, irradiance on a surface
    /// facing it) by median cut: repeatedly split the region of most energy across its longer
    /// angular side at its energy median. Each light sits at its region's energy-weighted mean
    /// direction and carries the sum of L dw over the region, so the total power is kept exactly.
    pub fn median_cut(&self, k: usize) -> Vec<(Vec3, Vec3)> {
        let energy = |x: usize, y: usize| {
            let l = self.radiance[y * self.width + x];
            (0.2126 * l.x + 0.7152 * l.y + 0.0722 * l.z) * self.texel_solid_angle(y)
        };
        let region_energy =
            |r: &[usize; 4]| -> f32 { (r[2]..r[3]).map(|y| (r[0]..r[1]).map(|x| energy(x, y)).sum::<f32>()).sum() };
        // Regions are [x0, x1, y0, y1).
        let mut regions = vec![[0, self.width, 0, self.height]];
        while regions.len() < k {
            let (i, _) = regions
                .iter()
                .enumerate()
                .filter(|(_, r)| r[1] - r[0] > 1 || r[3] - r[2] > 1)
                .map(|(i, r)| (i, region_energy(r)))
                .max_by(|a, b| a.1.total_cmp(&b.1))
                .unwrap_or((usize::MAX, 0.0));
            if i == usize::MAX {
                break;
            }
            let r = regions[i];
            let mid_theta = std::f32::consts::PI * ((r[2] + r[3]) as f32 * 0.5) / self.height as f32;
            let angular_w = (r[1] - r[0]) as f32 / self.width as f32 * 2.0 * mid_theta.sin().max(1e-3);
            let angular_h = (r[3] - r[2]) as f32 / self.height as f32;
            let split_x = (angular_w >= angular_h && r[1] - r[0] > 1) || r[3] - r[2] <= 1;
            let total = region_energy(&r);
            let (lo, hi) = if split_x { (r[0], r[1]) } else { (r[2], r[3]) };
            let mut acc = 0.0;
            let mut cut = lo + 1;
            for c in lo..hi - 1 {
                acc += if split_x {
                    (r[2]..r[3]).map(|y| energy(c, y)).sum::<f32>()
                } else {
                    (r[0]..r[1]).map(|x| energy(x, c)).sum::<f32>()
                };
                cut = c + 1;
                if acc >= 0.5 * total {
                    break;
                }
            }
            let (a, b) = if split_x {
                ([r[0], cut, r[2], r[3]], [cut, r[1], r[2], r[3]])
            } else {
                ([r[0], r[1], r[2], cut], [r[0], r[1], cut, r[3]])
            };
            regions[i] = a;
            regions.push(b);
        }
        regions
            .iter()
            .filter_map(|r| {
                let mut power = Vec3::ZERO;
                let mut mean = Vec3::ZERO;
                for y in r[2]..r[3] {
                    let dw = self.texel_solid_angle(y);
                    for x in r[0]..r[1] {
                        let d = Self::direction_of(self.width, self.height, x as f32 + 0.5, y as f32 + 0.5);
                        power += self.radiance[y * self.width + x] * dw;
                        mean += d * energy(x, y);
                    }
                }
                // Normalised through its largest component: the length of a sum of very bright
                // texels (1e20 and up) would overflow f32 and give a zero direction.
                let largest = mean.abs().max_element();
                let dir = if largest > 0.0 && largest.is_finite() {
                    (mean / largest).normalize()
                } else {
                    Self::direction_of(self.width, self.height, (r[0] + r[1]) as f32 * 0.5, (r[2] + r[3]) as f32 * 0.5)
                };
                (power.max_element() > 0.0).then_some((dir, power))
            })
            .collect()
    }
}

/// What a light is and how much it gives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    /// `direction`: unit vector towards the light; `irradiance` (W/m^2) on a surface facing it.
    Directional {
        /// Unit vector towards the light.
        direction: Vec3,
        /// W/m^2 per channel on a surface facing the light.
        irradiance: Vec3,
    },
    /// `intensity` in W/sr, falling off with the inverse square of the distance.
    Point {
        /// Position in world space (scene units).
        position: Vec3,
        /// W/sr per channel.
        intensity: Vec3,
    },
    /// A point light inside a cone about `axis` (pointing away from the light), smooth between
    /// the cosines of its inner and outer half-angles.
    Spot {
        /// Position in world space (scene units).
        position: Vec3,
        /// Unit axis of the cone, pointing away from the light.
        axis: Vec3,
        /// W/sr per channel on the axis.
        intensity: Vec3,
        /// Cosine of the outer half-angle, where the light reaches zero.
        cos_outer: f32,
        /// Cosine of the inner half-angle, inside which the light is at full intensity.
        cos_inner: f32,
    },
}

/// A scene light ready to render: its kind, its shadow map, and where it came from.
#[derive(Clone, Debug)]
pub struct PreparedLight {
    /// What the light is, with its direction or position and power.
    pub kind: LightKind,
    /// One of the environment light's median-cut directions (lights diffuse surfaces through
    /// the per-vertex cache; no specular lobe).
    pub environment: bool,
    /// Whether the scene asks for its shadows (`shadows` of the scene light).
    pub casts_shadow: bool,
    /// Its layer in the shadow-map array, when it casts shadows onto something.
    pub shadow_layer: Option<u32>,
    /// World -> the shadow map's clip space (depth 0..1).
    pub shadow_matrix: Mat4,
    /// One shadow-map texel in uv.
    pub shadow_texel: f32,
    /// Normal offset of shadow lookups (world units), half a texel's footprint.
    pub normal_offset: f32,
    /// Which scene light it came from (several for an environment).
    pub source: usize,
}

/// Turn scene lights into prepared lights. `bounds` is the bounding sphere (centre, radius) of
/// the shadow casters, which every shadow frustum must cover; `environment` is the loaded map or
/// sky. Shadow layers are assigned by [`assign_shadow_layers`].
pub fn prepare(
    lights: &[Light],
    environment: Option<&Environment>,
    bounds: (Vec3, f32),
    shadow_map_size: u32,
) -> Vec<PreparedLight> {
    let frame = ShadowFrame::new(bounds, shadow_map_size);
    let mut out = Vec::new();
    for (source, light) in lights.iter().enumerate() {
        match light {
            Light::Directional { direction, irradiance, shadows } => {
                out.push(frame.directional(Vec3::from(*direction), Vec3::from(*irradiance), false, *shadows, source))
            }
            Light::Point { position, intensity, shadows } => {
                let p = Vec3::from(*position);
                let kind = LightKind::Point { position: p, intensity: Vec3::from(*intensity) };
                out.push(frame.light(kind, frame.local(p, None), false, *shadows, source))
            }
            Light::Spot { position, direction, intensity, angle, softness, shadows } => {
                let p = Vec3::from(*position);
                let axis = unit(Vec3::from(*direction));
                let outer = angle.to_radians();
                let inner = outer * (1.0 - softness);
                let shadow = frame.local(p, Some((axis, (outer * 1.05).min(85f32.to_radians()))));
                let kind = LightKind::Spot {
                    position: p,
                    axis,
                    intensity: Vec3::from(*intensity),
                    cos_outer: outer.cos(),
                    cos_inner: inner.cos(),
                };
                out.push(frame.light(kind, shadow, false, *shadows, source))
            }
            Light::Environment { scale, directions, shadows, .. } => {
                if let Some(env) = environment {
                    for (dir, irradiance) in env.median_cut(*directions as usize) {
                        out.push(frame.directional(dir, irradiance * *scale, true, *shadows, source));
                    }
                }
            }
        }
    }
    // Key lights first, the environment's directions after: shading loops over the key lights
    // only (`key_light_count`), the environment reaching it through the per-vertex cache.
    out.sort_by_key(|l| l.environment);
    out
}

/// What every light's shadow map is fitted to: the casters' bounding sphere and the map's
/// resolution.
struct ShadowFrame {
    center: Vec3,
    radius: f32,
    /// One shadow-map texel in uv.
    texel: f32,
    /// A directional light's normal offset (world units).
    offset_ortho: f32,
}

impl ShadowFrame {
    fn new(bounds: (Vec3, f32), shadow_map_size: u32) -> ShadowFrame {
        // Any positive radius is a scale (the scene may be in micrometres); none, a unit one.
        let radius = if bounds.1 > 0.0 && bounds.1.is_finite() { bounds.1 } else { 1.0 };
        let center = bounds.0;
        let texel = 1.0 / shadow_map_size as f32;
        // Half a texel's world size: the normal offset of lookups (glsl/common/lights.glsl); for
        // local lights taken at the casters' centre. Measured on the default scene against ray
        // casting (tests/render.rs), 2048^2 maps: 0.5 texel leaves no sample off by 2%, 1 texel
        // 1%, 2 texels 2.25%; 1024^2 maps with 0.5 texel: 1.5%.
        let offset_ortho = 0.5 * (2.0 * radius) * texel;
        ShadowFrame { center, radius, texel, offset_ortho }
    }

    /// A prepared light of `kind` from scene light `source`, with its shadow `(matrix, normal
    /// offset)`; no shadow layer yet.
    fn light(
        &self,
        kind: LightKind,
        (matrix, offset): (Mat4, f32),
        environment: bool,
        casts_shadow: bool,
        source: usize,
    ) -> PreparedLight {
        PreparedLight {
            kind,
            environment,
            casts_shadow,
            shadow_layer: None,
            shadow_matrix: matrix,
            shadow_texel: self.texel,
            normal_offset: offset,
            source,
        }
    }

    /// A directional light towards `dir` (normalised here), its shadow map an orthographic
    /// view of the casters' sphere from outside it.
    fn directional(
        &self,
        dir: Vec3,
        irradiance: Vec3,
        environment: bool,
        casts_shadow: bool,
        source: usize,
    ) -> PreparedLight {
        let (center, radius) = (self.center, self.radius);
        let dir = unit(dir);
        let eye = center + dir * (2.0 * radius);
        let view = look_at_mat4(eye, center, any_up(dir));
        let proj = vulkan::orthographic(-radius, radius, -radius, radius, 0.0, 4.0 * radius);
        let kind = LightKind::Directional { direction: dir, irradiance };
        self.light(kind, (proj * view, self.offset_ortho), environment, casts_shadow, source)
    }

    /// A local light's shadow `(matrix, normal offset)` at `position`: a perspective view along
    /// a spot's `axis` (with its half-angle), or for a point light towards the casters' centre,
    /// wide enough to cover their sphere.
    fn local(&self, position: Vec3, axis: Option<(Vec3, f32)>) -> (Mat4, f32) {
        let (center, radius) = (self.center, self.radius);
        let to_center = center - position;
        let dist = to_center.length().max(radius * 1e-6);
        let (forward, half_angle) = match axis {
            Some((a, angle)) => (unit(a), angle),
            None => {
                // Cover the casters' bounding sphere; a light inside it gets a wide frustum and
                // loses the shadows of casters outside it (one map per light, no cube maps).
                let half = if dist > radius {
                    (radius / dist).asin() * 1.05
                } else {
                    log::warn!(
                        "a point light at {position} is inside the shadow casters' bounding sphere: its shadow map \
                         covers an 80-degree cone towards their centre, casters outside it cast no shadow"
                    );
                    80f32.to_radians()
                };
                // A light at the very centre looks down (any direction would do).
                (to_center.normalize_or(Vec3::NEG_Y), half.min(80f32.to_radians()))
            }
        };
        // Along the view axis: a spot looks along its own axis, not at the casters' centre.
        let axial = to_center.dot(forward);
        let near = (axial - radius).max(dist * 1e-3).max(radius * 1e-5);
        let far = (axial + radius).max(near * 2.0);
        let view = look_at_mat4(position, position + forward, any_up(forward));
        let proj = vulkan::perspective(2.0 * half_angle, 1.0, near, far);
        let offset = 0.5 * (2.0 * (center - position).length() * half_angle.tan()) * self.texel;
        (proj * view, offset)
    }
}

/// How many of `lights` (as `prepare` orders them) are not environment directions.
pub fn key_light_count(lights: &[PreparedLight]) -> usize {
    lights.iter().take_while(|l| !l.environment).count()
}

/// Whether every key light of `lights` is directional (the shading pass then leaves the point
/// and spot lights' falloff out of its pipeline).
pub fn key_lights_directional(lights: &[PreparedLight]) -> bool {
    lights.iter().filter(|l| !l.environment).all(|l| matches!(l.kind, LightKind::Directional { .. }))
}

/// Assign shadow-map layers to the lights that cast shadows; returns the layer count.
pub fn assign_shadow_layers(lights: &mut [PreparedLight], any_caster: bool) -> u32 {
    let mut layers = 0;
    for l in lights.iter_mut() {
        l.shadow_layer = (l.casts_shadow && any_caster).then(|| {
            layers += 1;
            layers - 1
        });
    }
    layers
}

/// `light` turned by `degrees` about the vertical axis through `centre` (directional lights
/// turn their direction, point and spot lights their position and axis), for animation
/// drivers; `None` for an environment light, which does not move.
pub fn orbit(light: &Light, centre: Vec3, degrees: f32) -> Option<Light> {
    let rotation = glam::Quat::from_rotation_y(degrees.to_radians());
    let turn = |v: [f32; 3]| (rotation * Vec3::from(v)).to_array();
    let turn_point = |p: [f32; 3]| (centre + rotation * (Vec3::from(p) - centre)).to_array();
    let mut light = light.clone();
    match &mut light {
        Light::Directional { direction, .. } => *direction = turn(*direction),
        Light::Point { position, .. } => *position = turn_point(*position),
        Light::Spot { position, direction, .. } => {
            *position = turn_point(*position);
            *direction = turn(*direction);
        }
        Light::Environment { .. } => return None,
    }
    Some(light)
}

/// `v` scaled to unit length, in f64: a non-zero vector whose squared length under- or
/// overflows f32 (components like 1e-30 or 1e30, which the scene checks allow) still gives a
/// finite direction.
pub fn unit(v: Vec3) -> Vec3 {
    v.as_dvec3().normalize().as_vec3()
}

fn any_up(dir: Vec3) -> Vec3 {
    if dir.y.abs() > 0.99 { Vec3::Z } else { Vec3::Y }
}
