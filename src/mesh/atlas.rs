//! A texture atlas of a mesh and its texels baked as surface samples, for the texture-space
//! gather (`render.gather = "texture"`, after Chang, Lin, Ho, Huang and Chuang 2008, who gather
//! from the irradiance stored in a texture of the surface).
//!
//! Charts: triangles grown across shared edges while their face normal stays within
//! [`CHART_COS`] of the chart's first triangle, each chart projected orthographically onto the
//! plane of that normal (so no triangle of a chart is flipped in the projection), in scene units.
//! Packing: the charts' rectangles on shelves, tallest first, one texel of padding on each side,
//! at one scale for all (texels per scene unit), the largest of a geometric sequence that fits.
//! Why our own and not xatlas: the `xatlas-rs` 0.1.3 crate's bindings were generated on Windows
//! and link against MSVC-mangled names (`?Create@xatlas@@...`), which no Linux build resolves
//! (docs/STUDY.md, "The texture-space gather").
//!
//! Baking: each texel whose centre a chart triangle covers is a sample at that point (position,
//! interpolated normal); a triangle's area is shared equally by the texels it covers, and a
//! triangle that covers no texel centre gives its area to the texel under its centroid. So the
//! texels' areas sum to the mesh's area exactly, at any resolution.

use super::{Mesh, NO_NEIGHBOUR};
use glam::{DVec2, DVec3, Vec3};

/// A chart keeps growing into a neighbouring triangle while the cosine between its face normal
/// and the chart's first normal is above this (about 53 degrees).
pub const CHART_COS: f64 = 0.6;
/// What [`Atlas::index`] holds where no texel is.
pub const NO_TEXEL: u32 = u32::MAX;
/// The smallest and largest atlas resolution (texels per side).
pub const MIN_RESOLUTION: u32 = 16;
/// See [`MIN_RESOLUTION`]; 2,048 keeps every texel coordinate in 16 bits and the index map at
/// 16 MiB.
pub const MAX_RESOLUTION: u32 = 2048;

/// The texture gather's local window: the `(2h + 1)^2` texels around a receiver's own texel are
/// summed exactly (`render::gather_texture`); `h` covers [`WINDOW_PROFILE_RADII`] RMS radii of
/// the widest channel's profile, from 1 to this many texels.
pub const MAX_WINDOW_RADIUS: u32 = 8;
/// The local window reaches this many RMS profile radii (`optics::Dipole::profile_radius`).
pub const WINDOW_PROFILE_RADII: f64 = 6.0;

/// The local window's half-width `h` in texels for an atlas of `scale` texels per unit and a
/// widest RMS profile radius of `profile_radius` units (infinite without absorption): enough
/// texels for [`WINDOW_PROFILE_RADII`] of it, 1 to [`MAX_WINDOW_RADIUS`].
pub fn window_radius(scale: f64, profile_radius: f64) -> u32 {
    let h = (WINDOW_PROFILE_RADII * profile_radius * scale).ceil();
    if h.is_nan() { MAX_WINDOW_RADIUS } else { h.clamp(1.0, f64::from(MAX_WINDOW_RADIUS)) as u32 }
}

/// The depth of the 4-ary sum tree over `texels` leaves: the least `L` with `4^L >= texels`. Its
/// nodes above the leaves number `(4^L - 1) / 3` ([`tree_nodes`]).
pub fn tree_levels(texels: usize) -> u32 {
    let mut levels = 0;
    while (1usize << (2 * levels)) < texels {
        levels += 1;
    }
    levels
}

/// Nodes above the leaves of a 4-ary sum tree of depth `levels`: `(4^levels - 1) / 3`.
pub fn tree_nodes(levels: u32) -> usize {
    ((1usize << (2 * levels)) - 1) / 3
}

/// One texel that carries surface: a sample of the texture-space gather.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Texel {
    /// The surface point at its centre (or the centroid of the small triangle it stands for).
    pub position: Vec3,
    /// The unit shading normal there.
    pub normal: Vec3,
    /// The surface area it stands for.
    pub area: f64,
    /// Its column and row in the atlas.
    pub coord: [u32; 2],
    /// The triangle it lies on, and its barycentric coordinates there.
    pub triangle: u32,
    /// Weights of the triangle's corners.
    pub barycentric: [f64; 3],
}

/// A mesh's atlas with its texels baked.
#[derive(Clone, Debug)]
pub struct Atlas {
    /// Texels per side.
    pub resolution: u32,
    /// The texels that carry surface, in Morton (Z) order of their coordinates: what the
    /// texture gather's sum tree is built over (its nodes are then compact squares of texels).
    pub texels: Vec<Texel>,
    /// `resolution^2` entries, row by row: the index in `texels` of the texel there, or
    /// [`NO_TEXEL`].
    pub index: Vec<u32>,
    /// Per mesh vertex, its texel (column, row): where it lies in the chart of its first
    /// triangle, clamped into the atlas.
    pub vertex_texel: Vec<[u32; 2]>,
    /// How many charts the mesh was cut into.
    pub charts: usize,
    /// Texels per scene unit (one for all charts; the mean over the surface for the mesh's own
    /// coordinates).
    pub scale: f64,
    /// Whose layout it is: the mesh's own coordinates, or charts of ours, and why.
    pub source: AtlasSource,
}

/// Whose layout an atlas is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AtlasSource {
    /// The mesh's own texture coordinates (OBJ `vt`, glTF `TEXCOORD_0`), scaled to the atlas.
    OwnUvs,
    /// The mesh cut into charts and packed here, because its own coordinates would not do.
    Charts(ChartsReason),
}

/// Why an atlas was cut into charts of ours instead of taking the mesh's own coordinates.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ChartsReason {
    /// The mesh has no texture coordinates (or not on every triangle).
    #[error("the mesh has no texture coordinates")]
    NoUvs,
    /// A corner's coordinates lie outside the unit square (tiled or wrapped textures).
    #[error("triangle {triangle}'s texture coordinates leave the unit square")]
    OutsideUnitSquare {
        /// The first such triangle.
        triangle: usize,
    },
    /// Two triangles' coordinates cover the same texel centre (mirrored or repeated parts).
    #[error("triangles {first} and {second} overlap in texture space")]
    Overlapping {
        /// The triangle that covered it first.
        first: usize,
        /// The one that covered it again.
        second: usize,
    },
}

impl std::fmt::Display for AtlasSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            AtlasSource::OwnUvs => f.write_str("the mesh's own texture coordinates"),
            AtlasSource::Charts(why) => write!(f, "charts of ours ({why})"),
        }
    }
}

/// The mesh's own coordinates in texels at `resolution`, per triangle corner, or why they will
/// not do: missing, outside the unit square, or two triangles over one texel centre.
fn own_uvs(mesh: &Mesh, resolution: u32) -> Result<Vec<[DVec2; 3]>, ChartsReason> {
    let corners = mesh.corner_uvs().ok_or(ChartsReason::NoUvs)?;
    let side = f64::from(resolution);
    let mut uvs = Vec::with_capacity(corners.len());
    for (triangle, c) in corners.iter().enumerate() {
        if c.iter().any(|uv| !(0.0..=1.0).contains(&uv.x) || !(0.0..=1.0).contains(&uv.y)) {
            return Err(ChartsReason::OutsideUnitSquare { triangle });
        }
        // Rows run down the atlas as v runs up the image.
        uvs.push(c.map(|uv| DVec2::new(f64::from(uv.x) * side, (1.0 - f64::from(uv.y)) * side)));
    }
    let mut owner = vec![u32::MAX; (resolution * resolution) as usize];
    for (triangle, uv) in uvs.iter().enumerate() {
        for [x, y] in inside(uv, resolution) {
            let slot = &mut owner[(y * resolution + x) as usize];
            if *slot != u32::MAX {
                return Err(ChartsReason::Overlapping { first: *slot as usize, second: triangle });
            }
            *slot = triangle as u32;
        }
    }
    Ok(uvs)
}

/// The texel centres in triangle `uv` (atlas coordinates) with their barycentric coordinates
/// there, each at least `margin` (0: the edges included); none for a triangle of no area.
fn centres(uv: &[DVec2; 3], resolution: u32, margin: f64) -> Vec<([u32; 2], [f64; 3])> {
    let lo = uv[0].min(uv[1]).min(uv[2]);
    let hi = uv[0].max(uv[1]).max(uv[2]);
    let max = f64::from(resolution - 1);
    let span = |a: f64, b: f64| (a - 0.5).ceil().clamp(0.0, max) as u32..=(b - 0.5).floor().clamp(0.0, max) as u32;
    let d = (uv[1] - uv[0]).perp_dot(uv[2] - uv[0]);
    let mut found = Vec::new();
    if d.abs() < 1e-300 {
        return found;
    }
    for y in span(lo.y, hi.y) {
        for x in span(lo.x, hi.x) {
            let p = DVec2::new(f64::from(x) + 0.5, f64::from(y) + 0.5);
            let b1 = (p - uv[0]).perp_dot(uv[2] - uv[0]) / d;
            let b2 = (uv[1] - uv[0]).perp_dot(p - uv[0]) / d;
            let b0 = 1.0 - b1 - b2;
            if b0 >= margin && b1 >= margin && b2 >= margin {
                found.push(([x, y], [b0, b1, b2]));
            }
        }
    }
    found
}

/// The texel centres strictly inside triangle `uv`: a centre on a shared edge is in neither
/// triangle, so neighbours never count as overlapping.
fn inside(uv: &[DVec2; 3], resolution: u32) -> impl Iterator<Item = [u32; 2]> {
    centres(uv, resolution, 1e-9).into_iter().map(|(xy, _)| xy)
}

/// Why a mesh got no atlas.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum AtlasError {
    /// The resolution is outside [`MIN_RESOLUTION`] to [`MAX_RESOLUTION`].
    #[error("atlas resolution {0} must be {MIN_RESOLUTION} to {MAX_RESOLUTION}")]
    Resolution(u32),
    /// Even at one texel per chart the charts do not fit.
    #[error("{charts} charts do not fit an atlas of {resolution}x{resolution} texels: raise the resolution")]
    TooManyCharts {
        /// The mesh's charts.
        charts: usize,
        /// The atlas's resolution.
        resolution: u32,
    },
}

/// One chart: its triangles, its projection plane and its place in the atlas.
struct Chart {
    triangles: Vec<usize>,
    origin: DVec3,
    axes: [DVec3; 2],
    /// The projection's bounding box in scene units (min, max).
    bounds: (DVec2, DVec2),
    /// Where its bounding box's minimum lands in the atlas, in texels.
    offset: DVec2,
}

impl Chart {
    /// Point `p` in the chart's plane coordinates (scene units).
    fn project(&self, p: DVec3) -> DVec2 {
        let d = p - self.origin;
        DVec2::new(d.dot(self.axes[0]), d.dot(self.axes[1]))
    }

    /// Atlas coordinates (texels) of point `p` at `scale` texels per unit.
    fn uv(&self, p: DVec3, scale: f64) -> DVec2 {
        self.offset + (self.project(p) - self.bounds.0) * scale
    }

    /// The chart's bounding box in its plane coordinates.
    fn measure(&mut self, mesh: &Mesh) {
        let mut bounds = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        for &t in &self.triangles {
            for p in mesh.corners(t) {
                let q = self.project(p);
                bounds = (bounds.0.min(q), bounds.1.max(q));
            }
        }
        self.bounds = bounds;
    }

    /// Turn the chart's axes in its plane to the rectangle of least area around it: one of its
    /// sides lies along an edge of the convex hull of its corners (Freeman and Shapira 1975).
    fn fit_rectangle(&mut self, mesh: &Mesh) {
        let points: Vec<DVec2> =
            self.triangles.iter().flat_map(|&t| mesh.corners(t)).map(|p| self.project(p)).collect();
        let hull = convex_hull(points.clone());
        let mut best = (f64::INFINITY, DVec2::X);
        for (i, &a) in hull.iter().enumerate() {
            let Some(edge) = (hull[(i + 1) % hull.len()] - a).try_normalize() else { continue };
            let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
            for &p in &hull {
                let q = DVec2::new(p.dot(edge), edge.perp_dot(p));
                (lo, hi) = (lo.min(q), hi.max(q));
            }
            let area = (hi - lo).x * (hi - lo).y;
            if area < best.0 {
                best = (area, edge);
            }
        }
        let (u, v) = (self.axes[0], self.axes[1]);
        let d = best.1;
        self.axes = [u * d.x + v * d.y, v * d.x - u * d.y];
        // Keep the plane's orientation: the second axis is the normal crossed with the first.
        if self.axes[0].cross(self.axes[1]).dot(u.cross(v)) < 0.0 {
            self.axes[1] = -self.axes[1];
        }
        self.measure(mesh);
    }

    /// Lay the chart on its side: a quarter turn in its plane.
    fn turn(&mut self) {
        let [u, v] = self.axes;
        self.axes = [v, -u];
        let (lo, hi) = self.bounds;
        self.bounds = (DVec2::new(lo.y, -hi.x), DVec2::new(hi.y, -lo.x));
    }
}

/// The convex hull of `points`, counter-clockwise (Andrew's monotone chain).
fn convex_hull(mut points: Vec<DVec2>) -> Vec<DVec2> {
    points.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    points.dedup();
    if points.len() < 3 {
        return points;
    }
    let mut hull: Vec<DVec2> = Vec::with_capacity(2 * points.len());
    for pass in [false, true] {
        let start = hull.len();
        let ordered: Box<dyn Iterator<Item = &DVec2>> =
            if pass { Box::new(points.iter().rev()) } else { Box::new(points.iter()) };
        for &p in ordered {
            while hull.len() >= start + 2
                && (hull[hull.len() - 1] - hull[hull.len() - 2]).perp_dot(p - hull[hull.len() - 2]) <= 0.0
            {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop();
    }
    hull
}

impl Atlas {
    /// The atlas of `mesh` at `resolution^2` texels: the mesh's own texture coordinates where
    /// it has them and they fit (`AtlasSource::OwnUvs`), else the mesh cut into charts and
    /// packed (`AtlasSource::Charts`, with why); then the texels baked.
    pub fn new(mesh: &Mesh, resolution: u32) -> Result<Atlas, AtlasError> {
        if !(MIN_RESOLUTION..=MAX_RESOLUTION).contains(&resolution) {
            return Err(AtlasError::Resolution(resolution));
        }
        match own_uvs(mesh, resolution) {
            Ok(uvs) => Ok(Atlas::of_own_uvs(mesh, &uvs, resolution)),
            Err(why) => Atlas::of_charts(mesh, resolution, why),
        }
    }

    /// The atlas of the mesh's own coordinates, scaled to texels (`uvs`, per triangle corner).
    fn of_own_uvs(mesh: &Mesh, uvs: &[[DVec2; 3]], resolution: u32) -> Atlas {
        let (texels, index) = bake(mesh, uvs.iter().enumerate().map(|(t, uv)| (t, *uv)), resolution);
        let mut vertex_texel = vec![None; mesh.positions().len()];
        for (t, uv) in uvs.iter().enumerate() {
            for (v, uv) in mesh.triangles()[t].iter().zip(uv) {
                vertex_texel[*v as usize].get_or_insert_with(|| texel_of(*uv, resolution));
            }
        }
        let texel_area: f64 = uvs.iter().map(|[a, b, c]| 0.5 * (*b - *a).perp_dot(*c - *a).abs()).sum();
        Atlas {
            resolution,
            texels,
            index,
            vertex_texel: vertex_texel.into_iter().map(Option::unwrap_or_default).collect(),
            charts: 0,
            // One figure for the whole mesh: the mean texels per unit over its surface.
            scale: (texel_area / mesh.total_area().max(f64::MIN_POSITIVE)).sqrt(),
            source: AtlasSource::OwnUvs,
        }
    }

    /// Cut `mesh` into charts, pack them into `resolution^2` texels and bake the texels.
    fn of_charts(mesh: &Mesh, resolution: u32, why: ChartsReason) -> Result<Atlas, AtlasError> {
        let mut charts = grow_charts(mesh);
        let scale = pack(mesh, &mut charts, mesh.total_area(), resolution)?;
        let placed =
            charts.iter().flat_map(|c| c.triangles.iter().map(move |&t| (t, mesh.corners(t).map(|p| c.uv(p, scale)))));
        let (texels, index) = bake(mesh, placed, resolution);
        let mut vertex_texel = vec![None; mesh.positions().len()];
        for chart in &charts {
            for &t in &chart.triangles {
                for v in mesh.triangles()[t] {
                    let slot = &mut vertex_texel[v as usize];
                    if slot.is_none() {
                        let uv = chart.uv(mesh.positions()[v as usize].as_dvec3(), scale);
                        *slot = Some(texel_of(uv, resolution));
                    }
                }
            }
        }
        let vertex_texel = vertex_texel.into_iter().map(Option::unwrap_or_default).collect();
        Ok(Atlas {
            resolution,
            texels,
            index,
            vertex_texel,
            charts: charts.len(),
            scale,
            source: AtlasSource::Charts(why),
        })
    }

    /// The texel at column `x`, row `y`, if one carries surface there.
    pub fn texel_at(&self, x: u32, y: u32) -> Option<u32> {
        let i = self.index[(y * self.resolution + x) as usize];
        (i != NO_TEXEL).then_some(i)
    }
}

/// The texel holding atlas point `uv`, clamped into the atlas.
fn texel_of(uv: DVec2, resolution: u32) -> [u32; 2] {
    let max = f64::from(resolution - 1);
    [uv.x.floor().clamp(0.0, max) as u32, uv.y.floor().clamp(0.0, max) as u32]
}

/// Charts by growing across edges from each triangle not yet taken, in triangle order, while the
/// face normal stays within [`CHART_COS`] of the seed's.
fn grow_charts(mesh: &Mesh) -> Vec<Chart> {
    let normals = mesh.face_normals();
    let mut taken = vec![false; mesh.triangles().len()];
    let mut charts = Vec::new();
    for seed in 0..taken.len() {
        if taken[seed] {
            continue;
        }
        let axis = normals[seed].as_dvec3();
        taken[seed] = true;
        let mut triangles = vec![seed];
        let mut next = 0;
        while next < triangles.len() {
            let t = triangles[next];
            next += 1;
            for n in mesh.neighbours()[t] {
                if n != NO_NEIGHBOUR && !taken[n as usize] && normals[n as usize].as_dvec3().dot(axis) > CHART_COS {
                    taken[n as usize] = true;
                    triangles.push(n as usize);
                }
            }
        }
        let axes = axis.any_orthonormal_pair();
        let origin = mesh.corners(seed)[0];
        let bounds = (DVec2::ZERO, DVec2::ZERO);
        let mut chart = Chart { triangles, origin, axes: [axes.0, axes.1], bounds, offset: DVec2::ZERO };
        chart.measure(mesh);
        charts.push(chart);
    }
    charts
}

/// The charts packed at the largest scale (texels per unit) at which they fit, found by
/// bisection to 0.1%: each chart turned to the rectangle of least area around it
/// ([`Chart::fit_rectangle`]), then laid by [`skyline`] at that scale; each chart's `offset`
/// (and, for those laid on their side, its axes) is set. An error when even a scale at which
/// every chart is a few texels does not fit.
fn pack(mesh: &Mesh, charts: &mut [Chart], area: f64, resolution: u32) -> Result<f64, AtlasError> {
    let side = f64::from(resolution);
    for chart in charts.iter_mut() {
        chart.fit_rectangle(mesh);
    }
    let full = (side * side / area.max(f64::MIN_POSITIVE)).sqrt();
    let (mut lo, mut hi) = (full * 0.5, full);
    let mut best = None;
    for _ in 0..40 {
        if let Some(layout) = skyline(mesh, charts, lo, resolution) {
            best = Some((lo, layout));
            break;
        }
        (hi, lo) = (lo, lo * 0.7);
    }
    let Some((mut scale, mut layout)) = best else {
        return Err(AtlasError::TooManyCharts { charts: charts.len(), resolution });
    };
    while hi / lo > 1.001 {
        let mid = (lo * hi).sqrt();
        match skyline(mesh, charts, mid, resolution) {
            Some(found) => (lo, scale, layout) = (mid, mid, found),
            None => hi = mid,
        }
    }
    for (chart, (offset, turned)) in charts.iter_mut().zip(layout) {
        if turned {
            chart.turn();
        }
        chart.offset = offset;
    }
    Ok(scale)
}

/// The columns a chart covers at some scale, each with the lowest and highest row a triangle's
/// box reaches, relative to the chart's own corner: the shape [`skyline`] lays.
struct Profile {
    /// Per column, (lowest row, highest row); `None` where no triangle reaches.
    columns: Vec<Option<(i64, i64)>>,
}

impl Profile {
    /// The texel cells the chart's triangles' boxes touch at `scale`: two charts whose cells
    /// differ share no texel centre, so they need no gap (the texture gather's local window
    /// takes the texels around a receiver by their own positions, whichever chart they are
    /// of). With `turned`, the chart laid on its side.
    fn of(mesh: &Mesh, chart: &Chart, scale: f64, turned: bool) -> Profile {
        let extent = (chart.bounds.1 - chart.bounds.0) * scale;
        let width = if turned { extent.y } else { extent.x }.floor() as usize + 1;
        let mut columns = vec![None; width];
        for &t in &chart.triangles {
            let uv = mesh.corners(t).map(|p| {
                let q = (chart.project(p) - chart.bounds.0) * scale;
                if turned { DVec2::new(q.y, extent.x - q.x) } else { q }
            });
            let lo = uv[0].min(uv[1]).min(uv[2]);
            let hi = uv[0].max(uv[1]).max(uv[2]);
            let (x0, x1) = (lo.x.floor() as i64, (hi.x.floor() as i64).min(width as i64 - 1));
            let (y0, y1) = (lo.y.floor() as i64, hi.y.floor() as i64 + 1);
            for column in &mut columns[x0.max(0) as usize..=x1.max(0) as usize] {
                *column = Some(column.map_or((y0, y1), |(a, b): (i64, i64)| (a.min(y0), b.max(y1))));
            }
        }
        Profile { columns }
    }

    /// Where the profile rests on `sky` (each column's first free row) with its first column
    /// at `x`: the row its corner goes to, the highest row it then reaches, and the texels it
    /// leaves empty beneath it.
    fn rest(&self, sky: &[i64], x: usize) -> (i64, i64, i64) {
        let mut y = 0;
        for (c, column) in self.columns.iter().enumerate() {
            if let Some((bottom, _)) = column {
                y = y.max(sky[x + c] - bottom);
            }
        }
        let (mut top, mut holes) = (y, 0);
        for (c, column) in self.columns.iter().enumerate() {
            if let Some((bottom, high)) = column {
                top = top.max(y + high);
                holes += y + bottom - sky[x + c];
            }
        }
        (y, top, holes)
    }
}

/// Tetris-like packing at `scale`: each chart, largest first, in whichever of its two
/// orientations and at whichever column leaves the lowest top, dropped until it rests on what is
/// already there (each column's first free row; holes under overhangs stay empty). Per chart
/// its offset (texels, its box's corner) and whether it lies on its side, or `None` when the
/// charts overflow the atlas.
fn skyline(mesh: &Mesh, charts: &[Chart], scale: f64, resolution: u32) -> Option<Vec<(DVec2, bool)>> {
    let side = resolution as usize;
    let mut sky = vec![0i64; side];
    let mut order: Vec<usize> = (0..charts.len()).collect();
    let size = |c: &Chart| (c.bounds.1 - c.bounds.0).max_element();
    order.sort_by(|&a, &b| size(&charts[b]).total_cmp(&size(&charts[a])));
    let mut layout = vec![(DVec2::ZERO, false); charts.len()];
    for i in order {
        let profiles = [false, true].map(|turned| Profile::of(mesh, &charts[i], scale, turned));
        let mut best: Option<(i64, usize, i64, usize, i64)> = None;
        for (p, profile) in profiles.iter().enumerate() {
            let width = profile.columns.len();
            for x in 0..=side.saturating_sub(width) {
                let (y, top, holes) = profile.rest(&sky, x);
                // The texels this placement spends: those it leaves empty beneath it, and the
                // rows it adds above the lowest it could reach.
                let cost = holes + top * width as i64;
                if width <= side && best.is_none_or(|b| cost < b.0) {
                    best = Some((cost, x, y, p, top));
                }
            }
        }
        let (_, x, y, p, top) = best?;
        if top > side as i64 {
            return None;
        }
        for (c, column) in profiles[p].columns.iter().enumerate() {
            if let Some((_, high)) = column {
                sky[x + c] = sky[x + c].max(y + high);
            }
        }
        layout[i] = (DVec2::new(x as f64, y as f64), p == 1);
    }
    Some(layout)
}

/// The texels every triangle covers at its atlas coordinates `placed` (triangle, corners in
/// texels; see the module's doc), in Morton order, and the index map.
fn bake(mesh: &Mesh, placed: impl Iterator<Item = (usize, [DVec2; 3])>, resolution: u32) -> (Vec<Texel>, Vec<u32>) {
    let mut index = vec![NO_TEXEL; (resolution * resolution) as usize];
    let mut texels: Vec<Texel> = Vec::new();
    for (t, uv) in placed {
        let covered = cover(&uv, resolution, &mut index, texels.len() as u32);
        let area = mesh.triangle_areas()[t];
        if covered.is_empty() {
            let centroid = (uv[0] + uv[1] + uv[2]) / 3.0;
            let [x, y] = texel_of(centroid, resolution);
            let slot = &mut index[(y * resolution + x) as usize];
            if *slot == NO_TEXEL {
                *slot = texels.len() as u32;
                texels.push(texel(mesh, t, [1.0 / 3.0; 3], [x, y], 0.0));
            }
            texels[*slot as usize].area += area;
            continue;
        }
        let share = area / covered.len() as f64;
        for ([x, y], bary) in covered {
            texels.push(texel(mesh, t, bary, [x, y], share));
        }
    }
    let mut order: Vec<u32> = (0..texels.len() as u32).collect();
    order.sort_by_key(|&i| morton(texels[i as usize].coord));
    let texels: Vec<Texel> = order.iter().map(|&i| texels[i as usize]).collect();
    index.fill(NO_TEXEL);
    for (i, t) in texels.iter().enumerate() {
        index[(t.coord[1] * resolution + t.coord[0]) as usize] = i as u32;
    }
    (texels, index)
}

fn texel(mesh: &Mesh, t: usize, barycentric: [f64; 3], coord: [u32; 2], area: f64) -> Texel {
    Texel {
        position: mesh.point(t, barycentric).as_vec3(),
        normal: mesh.normal_at(t, barycentric),
        area,
        coord,
        triangle: t as u32,
        barycentric,
    }
}

/// The texel centres inside the triangle `uv` (atlas coordinates) not yet taken, each claimed in
/// `index` for the texel numbered `next` on, with their barycentric coordinates.
fn cover(uv: &[DVec2; 3], resolution: u32, index: &mut [u32], next: u32) -> Vec<([u32; 2], [f64; 3])> {
    let mut covered = Vec::new();
    for ([x, y], bary) in centres(uv, resolution, 0.0) {
        let slot = &mut index[(y * resolution + x) as usize];
        if *slot == NO_TEXEL {
            *slot = next + covered.len() as u32;
            covered.push(([x, y], bary));
        }
    }
    covered
}

/// The Morton (Z-order) key of a texel: its column's and row's bits interleaved.
pub fn morton([x, y]: [u32; 2]) -> u64 {
    let spread = |v: u32| {
        let mut v = u64::from(v) & 0xffff_ffff;
        v = (v | (v << 16)) & 0x0000_ffff_0000_ffff;
        v = (v | (v << 8)) & 0x00ff_00ff_00ff_00ff;
        v = (v | (v << 4)) & 0x0f0f_0f0f_0f0f_0f0f;
        v = (v | (v << 2)) & 0x3333_3333_3333_3333;
        (v | (v << 1)) & 0x5555_5555_5555_5555
    };
    spread(x) | (spread(y) << 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(n: u32) -> Mesh {
        crate::mesh::shapes::plane(1.0, n).unwrap()
    }

    #[test]
    fn texel_areas_sum_to_the_mesh_area_at_any_resolution() {
        let sphere = crate::mesh::shapes::sphere(1.0, 24).unwrap();
        for mesh in [square(8), sphere] {
            for resolution in [16, 64, 256] {
                let atlas = Atlas::new(&mesh, resolution).unwrap();
                let sum: f64 = atlas.texels.iter().map(|t| t.area).sum();
                assert!((sum - mesh.total_area()).abs() < 1e-9 * mesh.total_area(), "{resolution}: {sum}");
            }
        }
    }

    #[test]
    fn a_plane_is_one_chart_with_equal_texels() {
        let atlas = Atlas::new(&square(8), 64).unwrap();
        assert_eq!(atlas.charts, 1);
        let areas: Vec<f64> = atlas.texels.iter().map(|t| t.area).collect();
        let mean = areas.iter().sum::<f64>() / areas.len() as f64;
        // Every triangle covers about the same number of texel centres.
        assert!(areas.iter().all(|a| (a / mean - 1.0).abs() < 0.5), "{mean}");
    }

    #[test]
    fn the_index_map_and_the_texels_agree() {
        let atlas = Atlas::new(&crate::mesh::shapes::sphere(1.0, 16).unwrap(), 64).unwrap();
        for (i, t) in atlas.texels.iter().enumerate() {
            assert_eq!(atlas.texel_at(t.coord[0], t.coord[1]), Some(i as u32));
        }
        assert!(atlas.texels.windows(2).all(|w| morton(w[0].coord) < morton(w[1].coord)));
    }

    #[test]
    fn a_resolution_out_of_range_is_an_error() {
        assert_eq!(Atlas::new(&square(2), 8).unwrap_err(), AtlasError::Resolution(8));
    }
}
