//! `GpuScene`: a prepared scene's data on the GPU, packed once (`records`) and uploaded: the
//! shared vertex and index buffers, object, sample and light records, and the buffers the passes
//! write and read between frames (splat output, exitance, cached environment irradiance). The
//! passes get their inputs from here; only lights and object records change after creation.

pub use super::ranges::{DrawRange, LevelRange, ObjectRange, Receiver, TextureRange};
use super::records::{
    BeamNodeRecord, BeamSourceRecord, BvhNodeRecord, BvhTriangleRecord, LightGpu, NodePowerRecord, ObjectRecord,
    ReceiverGroupRecord, SampleRecord, SplatRecord, TreeNodeRecord, Vertex,
};
use super::resource::{Resource, SceneBuffers};
use crate::gpu::{Buffer, BufferDesc, Gpu, GpuResult};
use crate::mesh::enclosure;
use crate::optics::kernel::NEAR_BLEND_RADIUS;
use crate::sampling::{NODE_ITEM, SampleTree};
use crate::scene::build::PreparedScene;
use ash::vk;
use std::sync::Arc;

/// A prepared scene's data on the GPU: device-local buffers the passes bind, and the ranges and
/// counts they dispatch and draw with. The passes' descriptor sets point into these buffers, so the
/// passes must be dropped first (`Renderer` declares its passes before its `GpuScene`). Only the
/// light records and shadow matrices change after creation (`set_lights`).
pub struct GpuScene {
    /// The buffers of every scene resource (`resource::SceneBuffers`).
    pub(in crate::render) buffers: SceneBuffers,
    /// u32 triangle indices of every object, relative to its first vertex
    /// (`DrawRange::vertex_offset`).
    pub indices: Buffer,
    /// Per object, in scene order: its levels of detail, the whole mesh first.
    pub levels: Vec<Vec<LevelRange>>,
    /// The objects that cast shadows: (scene index, the level of detail drawn into shadow maps).
    /// The level is the coarsest within half a shadow-map texel of the whole mesh (a texel of a
    /// map spanning the casters' bounding sphere), so the full-detail surface the splat and
    /// shading look up from never falls behind a simplified caster (self-shadowing).
    pub casters: Vec<(usize, usize)>,
    /// Per object, in scene order: its between-points channels and their tables' places.
    pub beams: Vec<Option<super::beam_tables::ObjectBeams>>,
    /// The nodes' stand-ins' first entry in `beam_sources`: `tree_order`'s length.
    pub beam_standins: u32,
    /// Per object, in scene order: where its transport kernel lies, if it has one.
    pub transport: Vec<Option<Vec<super::transport_tables::LevelTransport>>>,
    /// Triangles in `bvh_triangles`: 0 when nothing casts a shadow.
    pub caster_triangles: u32,
    /// How far a shadow ray starts off the surface, along the normal, and the least distance
    /// at which it counts a hit (`PreparedScene::ray_offset`, as the truth's rays).
    pub ray_offset: f32,
    /// Per object, in scene order: its atlas and sum tree's place (`TextureRange`).
    pub textures: Vec<TextureRange>,
    /// World -> clip matrix of each shadow-map layer.
    pub light_matrices: Vec<[[f32; 4]; 4]>,
    /// The translucent objects, in scene order: what the gathers dispatch over.
    pub receivers: Vec<Receiver>,
    /// Per entry of `receivers`, the hierarchical gather's receivers at each coarser level of
    /// detail (level 1 first): the level's vertices grouped and cut anew, so that a frame
    /// drawing a coarse level gathers at its vertices only. Empty for other gathers.
    pub coarser_receivers: Vec<Vec<Receiver>>,
    /// Per entry of `receivers`, its hierarchy's nodes by height, leaves first
    /// (`sampling::SampleTree::by_height`): each height's first entry in `tree_order` and its
    /// node count. The hierarchical gather's stage 0 aggregates them one height at a time.
    pub node_heights: Vec<Vec<[u32; 2]>>,
    /// Vertices of all objects together.
    pub vertex_count: u32,
    /// Sample points of all objects together.
    pub sample_count: u32,
    /// Prepared lights (environment directions included): the records in `lights`.
    pub light_count: u32,
    /// Lights that are not environment directions; they come first in the light buffer.
    pub key_light_count: u32,
    /// Whether every key light is directional (`lights::key_lights_directional`), for the
    /// shading pass's choice of pipeline; kept with the records `set_lights` uploads.
    pub key_lights_directional: bool,
    /// Light records waiting to be copied into `lights` by the next recorded frame.
    pending_lights: Option<Vec<LightGpu>>,
    /// The object records as last packed; copied into `objects` by the next recorded frame when
    /// `pending_objects` (a material or the planner's local channels changed).
    object_records: Vec<ObjectRecord>,
    pending_objects: bool,
}

/// The records a frame uploads before its passes (`GpuScene::uploads`).
#[derive(Clone, Debug)]
pub(in crate::render) struct PendingUploads {
    lights: Option<Vec<LightGpu>>,
    objects: Vec<ObjectRecord>,
    objects_pending: bool,
}

/// Every object's levels of detail packed (`pack_levels`).
struct PackedLevels {
    /// The shared index buffer's contents.
    indices: Vec<u32>,
    /// Each object's level ranges.
    levels: Vec<Vec<LevelRange>>,
    /// The shadow casters with the level drawn into shadow maps.
    casters: Vec<(usize, usize)>,
    /// The translucent objects' level vertex lists (opaque objects have none: they are never
    /// gathered).
    level_vertices: Vec<u32>,
}

fn pack_levels(scene: &PreparedScene) -> PackedLevels {
    let (mut indices, mut levels, mut casters, mut level_vertices) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut first_vertex = 0u32;
    for (i, o) in scene.objects.iter().enumerate() {
        let translucent = matches!(o.material, crate::scene::build::ResolvedMaterial::Translucent { .. });
        let mut ranges = Vec::new();
        for level in &o.levels {
            let draw = DrawRange {
                first_index: indices.len() as u32,
                index_count: 3 * level.triangles.len() as u32,
                vertex_offset: first_vertex as i32,
            };
            indices.extend(level.triangles.iter().flatten());
            let first_entry = level_vertices.len() as u32;
            if translucent {
                level_vertices.extend(&level.vertices);
            }
            ranges.push(LevelRange {
                draw,
                first_entry,
                vertex_count: level_vertices.len() as u32 - first_entry,
                enclosure: enclosure(o.mesh.positions(), &level.triangles),
                bounds: level.bounds(o.mesh.positions()),
                reach: crate::mesh::facing::longest_edge(o.mesh.positions(), &level.triangles),
            });
        }
        levels.push(ranges);
        if o.casts_shadow {
            let level = o.levels.iter().rposition(|l| l.error <= 0.5 * scene.shadow_texel()).unwrap_or(0);
            casters.push((i, level));
        }
        first_vertex += o.mesh.positions().len() as u32;
    }
    PackedLevels { indices, levels, casters, level_vertices }
}

/// Per vertex of every object, in scene order, its facing cone (`mesh::facing::vertex_cones`)
/// over the triangles of each of its levels, with the enclosures `pack_levels` found.
fn receiver_cones(scene: &PreparedScene, levels: &[Vec<LevelRange>]) -> Vec<[f32; 4]> {
    let cones = scene.objects.iter().zip(levels).flat_map(|(o, ranges)| {
        let triangles = o.levels.iter().zip(ranges).map(|(l, r)| (&l.triangles[..], r.enclosure));
        crate::mesh::facing::vertex_cones(o.mesh.positions(), triangles)
    });
    cones.collect()
}

fn storage(gpu: &Arc<Gpu>, name: &str, bytes: u64, extra: vk::BufferUsageFlags) -> GpuResult<Buffer> {
    Buffer::new(gpu, &BufferDesc::gpu_only(name, bytes.max(16), vk::BufferUsageFlags::STORAGE_BUFFER | extra))
}

fn upload<T: bytemuck::Pod>(gpu: &Arc<Gpu>, name: &str, data: &[T], usage: vk::BufferUsageFlags) -> GpuResult<Buffer> {
    let bytes = std::mem::size_of_val(data) as u64;
    let mut buffer = storage(gpu, name, bytes, usage)?;
    if bytes > 0 {
        buffer.write(0, data)?;
    }
    Ok(buffer)
}

/// What `PackedObjects::receivers_at` groups: an object's receivers at one level of detail.
#[derive(Clone, Copy)]
struct ReceiversAt<'a> {
    tree: &'a SampleTree,
    /// Object-relative vertex indices.
    vertices: &'a [u32],
    /// The hierarchical gather's epsilon, when the scene gathers hierarchically.
    epsilon: Option<f64>,
    /// Whether the scene gathers sparsely (blend lists wanted).
    sparse: bool,
    /// The object's first vertex, first sample and first node.
    first: [u32; 3],
}

/// Every object's records packed for the shared buffers, in scene order: vertices, samples and
/// object records, and for each translucent object its sample hierarchy, receiver groups and the
/// gathers' item lists, made absolute.
#[derive(Default)]
struct PackedObjects {
    vertices: Vec<Vertex>,
    objects: Vec<ObjectRecord>,
    samples: Vec<SampleRecord>,
    vertex_boundary: Vec<[f32; 2]>,
    receivers: Vec<Receiver>,
    coarser_receivers: Vec<Vec<Receiver>>,
    node_heights: Vec<Vec<[u32; 2]>>,
    tree_nodes: Vec<TreeNodeRecord>,
    tree_order: Vec<u32>,
    receiver_order: Vec<u32>,
    receiver_groups: Vec<ReceiverGroupRecord>,
    group_items: Vec<u32>,
    blend_items: Vec<u32>,
    texel_coords: Vec<u32>,
    texel_index: Vec<u32>,
    vertex_texel: Vec<u32>,
    pyramid_nodes: usize,
    textures: Vec<TextureRange>,
    bvh_nodes: Vec<BvhNodeRecord>,
    bvh_triangles: Vec<BvhTriangleRecord>,
    /// Per object, its sample hierarchy where a channel takes single scattering between
    /// points (`beam_gather::pack_tables` reads it rather than building it again).
    beam_trees: Vec<Option<crate::sampling::SampleTree>>,
    /// Per object, its first vertex and first sample.
    firsts: Vec<[u32; 2]>,
}

impl PackedObjects {
    fn of(scene: &PreparedScene) -> PackedObjects {
        let mut packed = PackedObjects { beam_trees: vec![None; scene.objects.len()], ..Default::default() };
        for (i, o) in scene.objects.iter().enumerate() {
            let first = [packed.vertices.len() as u32, packed.samples.len() as u32];
            packed.firsts.push(first);
            packed.object(o);
            if matches!(o.material, crate::scene::build::ResolvedMaterial::Translucent { .. }) {
                packed.receiver(scene, i, o, first);
            }
        }
        packed.casters(scene);
        packed
    }

    /// The shadow casters' hierarchy, when the splat casts rays into it and there is anything to
    /// splat and to cast a shadow.
    fn casters(&mut self, scene: &PreparedScene) {
        let rays = scene.scene.file.render.splat_visibility != crate::scene::SplatVisibility::ShadowMaps;
        if !rays || !scene.any_caster || self.samples.is_empty() {
            return;
        }
        let (nodes, triangles) = scene.occluders().flat();
        self.bvh_nodes = nodes.iter().map(BvhNodeRecord::new).collect();
        self.bvh_triangles = triangles.iter().map(BvhTriangleRecord::new).collect();
    }

    /// An object's vertices, boundary distances, samples and record.
    fn object(&mut self, o: &crate::scene::build::PreparedObject) {
        let (first_vertex, first_sample) = (self.vertices.len() as u32, self.samples.len() as u32);
        let normals = o.mesh.vertex_normals();
        let positions = o.mesh.positions();
        self.vertices.extend(
            positions.iter().zip(normals).map(|(p, n)| Vertex { position: p.to_array(), normal: n.to_array() }),
        );
        if matches!(o.material, crate::scene::build::ResolvedMaterial::Translucent { .. }) {
            self.vertex_boundary.extend(o.mesh.boundary_distances());
        } else {
            self.vertex_boundary.extend(std::iter::repeat_n([crate::mesh::NO_BOUNDARY; 2], positions.len()));
        }
        let faces = o.mesh.face_normals();
        self.samples.extend(o.samples.iter().map(|s| SampleRecord::new(s, faces[s.triangle as usize])));
        let ranges = [first_vertex, positions.len() as u32, first_sample, o.samples.len() as u32];
        self.objects.push(ObjectRecord::new(o, ranges));
        self.atlas(o);
    }

    /// Object `o`'s atlas, when it has one: its texels' and vertices' coordinates, its index
    /// map and its sum tree's place; zeros otherwise.
    fn atlas(&mut self, o: &crate::scene::build::PreparedObject) {
        let pack = |[x, y]: [u32; 2]| x | (y << 16);
        let Some(atlas) = &o.atlas else {
            self.texel_coords.extend(std::iter::repeat_n(0, o.samples.len()));
            self.vertex_texel.extend(std::iter::repeat_n(0, o.mesh.positions().len()));
            self.textures.push(TextureRange::default());
            return;
        };
        self.texel_coords.extend(atlas.texels.iter().map(|t| pack(t.coord)));
        self.vertex_texel.extend(atlas.vertex_texel.iter().map(|&c| pack(c)));
        let levels = crate::mesh::atlas::tree_levels(atlas.texels.len());
        self.textures.push(TextureRange {
            levels,
            first_node: self.pyramid_nodes as u32,
            first_index: self.texel_index.len() as u32,
            resolution: atlas.resolution,
            radius: o.window_radius().unwrap_or(1),
        });
        self.texel_index.extend(&atlas.index);
        self.pyramid_nodes += crate::mesh::atlas::tree_nodes(levels);
    }

    /// Translucent object `i`'s hierarchy, receiver groups and their item lists; `first` is its
    /// first vertex and first sample. A hierarchical gather gets receivers at every coarser
    /// level of detail too.
    fn receiver(&mut self, scene: &PreparedScene, i: usize, o: &crate::scene::build::PreparedObject, first: [u32; 2]) {
        let [first_vertex, first_sample] = first;
        let render = &scene.scene.file.render;
        let tree = o.sample_tree();
        let (first_node, first_entry) = (self.tree_nodes.len() as u32, self.tree_order.len() as u32);
        self.tree_nodes.extend(tree.nodes.iter().map(|n| TreeNodeRecord::new(n, first_node, first_entry)));
        self.tree_order.extend(tree.order.iter().map(|k| first_sample + k));
        let mut heights = Vec::new();
        for nodes in tree.by_height() {
            heights.push([self.tree_order.len() as u32, nodes.len() as u32]);
            self.tree_order.extend(nodes.iter().map(|n| first_node + n));
        }
        self.node_heights.push(heights);
        let hierarchical = render.gather == crate::scene::GatherMode::Hierarchical;
        let epsilon = hierarchical.then_some(render.gather_epsilon as f64);
        let sparse = render.gather == crate::scene::GatherMode::Sparse;
        let whole: Vec<u32> = (0..o.mesh.positions().len() as u32).collect();
        let whole_mesh = ReceiversAt {
            tree: &tree,
            vertices: &whole,
            epsilon,
            sparse,
            first: [first_vertex, first_sample, first_node],
        };
        let receiver = self.receivers_at(i, o, whole_mesh);
        self.receivers.push(receiver);
        let coarser = if hierarchical {
            o.levels
                .iter()
                .skip(1)
                .map(|l| self.receivers_at(i, o, ReceiversAt { vertices: &l.vertices, ..whole_mesh }))
                .collect()
        } else {
            Vec::new()
        };
        self.coarser_receivers.push(coarser);
        self.beam_trees[i] = o.single_channels().contains(&true).then_some(tree);
    }

    /// Object `i`'s receivers `at.vertices` (object-relative indices) grouped, with each group's
    /// hierarchical cut (when `at.epsilon` is given) and sparse blend list.
    fn receivers_at(&mut self, i: usize, o: &crate::scene::build::PreparedObject, at: ReceiversAt) -> Receiver {
        let [first_vertex, first_sample, first_node] = at.first;
        let positions: Vec<glam::DVec3> =
            at.vertices.iter().map(|&v| o.mesh.positions()[v as usize].as_dvec3()).collect();
        let groups = crate::sampling::ReceiverGroups::new(&positions);
        let (first_receiver, first_group) = (self.receiver_order.len() as u32, self.receiver_groups.len() as u32);
        self.receiver_order.extend(groups.order.iter().map(|&k| first_vertex + at.vertices[k as usize]));
        let first = [first_node, first_sample];
        if let Some(epsilon) = at.epsilon {
            // The hierarchical gather: one record per receiver, in group order, with its own cut.
            let cuts = o.gather_cuts(at.tree, &groups, &positions, epsilon);
            for (n, &k) in groups.order.iter().enumerate() {
                self.group((positions[k as usize].as_vec3().to_array(), 0.0), cuts.of(n), None, first);
            }
        } else {
            let samples: Vec<glam::DVec3> = o.samples.iter().map(|s| s.position.as_dvec3()).collect();
            let areas: Vec<f64> = o.samples.iter().map(|s| s.area).collect();
            for &group in &groups.bounds {
                let blend = at.sparse.then(|| at.tree.within_reach(group, &samples, &areas, NEAR_BLEND_RADIUS));
                self.group(group, &[], blend.as_deref(), first);
            }
        }
        Receiver {
            object: i as u32,
            vertex_count: at.vertices.len() as u32,
            sample_count: o.samples.len() as u32,
            first_node,
            node_count: at.tree.nodes.len() as u32,
            first_receiver,
            first_group,
        }
    }

    /// One receiver group: its hierarchical items (nodes first, then samples: the shader sums
    /// each kind in its own loop) and its sparse blend list, made absolute with `first` (the
    /// object's first node and first sample).
    fn group(&mut self, ([x, y, z], r): ([f32; 3], f32), items: &[u32], blend: Option<&[u32]>, first: [u32; 2]) {
        let [first_node, first_sample] = first;
        let start = self.group_items.len() as u32;
        self.group_items.extend(items.iter().filter(|&&it| it & NODE_ITEM != 0).map(|&it| it + first_node));
        let node_count = self.group_items.len() as u32 - start;
        self.group_items.extend(items.iter().filter(|&&it| it & NODE_ITEM == 0).map(|&it| it + first_sample));
        let sample_count = self.group_items.len() as u32 - start - node_count;
        let first_blend = self.blend_items.len() as u32;
        self.blend_items.extend(blend.unwrap_or_default().iter().map(|s| s + first_sample));
        self.receiver_groups.push(ReceiverGroupRecord {
            center_radius: [x, y, z, r],
            items: [start, node_count, sample_count, 0],
            blend: [first_blend, self.blend_items.len() as u32 - first_blend, 0, 0],
        });
    }

    /// The hierarchical gather's lists must fit one storage-buffer range.
    fn check_lists(&self, gpu: &Gpu, epsilon: f32) -> GpuResult<()> {
        let what =
            || format!("bytes of the hierarchical gather's item lists at render.gather_epsilon {epsilon} (raise it)");
        check_range(gpu, 4 * self.group_items.len() as u64, what)
    }

    /// The splat's caster hierarchy must fit one storage-buffer range.
    fn check_casters(&self, gpu: &Gpu) -> GpuResult<()> {
        let bytes = std::mem::size_of_val(self.bvh_triangles.as_slice()) as u64;
        check_range(gpu, bytes, || {
            "bytes of the splat's shadow casters' triangles (render.splat_visibility = \"shadow_maps\" needs none)"
                .into()
        })
    }
}

/// `bytes` of one storage buffer against the device's range, the error naming `what`.
fn check_range(gpu: &Gpu, bytes: u64, what: impl Fn() -> String) -> GpuResult<()> {
    let range = gpu.properties().limits.max_storage_buffer_range as u64;
    if bytes <= range {
        return Ok(());
    }
    Err(crate::gpu::GpuError::Limit { what: what(), value: bytes, limit: range, name: "maxStorageBufferRange" })
}

impl GpuScene {
    /// Pack the scene's records (`records`) and upload them before any frame: vertices, indices,
    /// objects, samples and lights. Exitance and environment irradiance start at zero; the splat
    /// buffer is left for the splat pass. Every buffer has at least 16 bytes, so an empty part of
    /// the scene still binds.
    pub fn new(gpu: &Arc<Gpu>, scene: &PreparedScene) -> GpuResult<GpuScene> {
        let levels = pack_levels(scene);
        let packed = PackedObjects::of(scene);
        packed.check_lists(gpu, scene.scene.file.render.gather_epsilon)?;
        packed.check_casters(gpu)?;
        let mut gpu_scene = Self::upload(gpu, scene, packed, levels)?;
        gpu_scene.set_lights(scene);
        // Before any frame the buffer is idle: written from the host directly.
        if let Some(records) = gpu_scene.pending_lights.take().filter(|r| !r.is_empty()) {
            gpu_scene.buffers.lights.write(0, &records)?;
        }
        Ok(gpu_scene)
    }

    /// Every buffer made and filled from the packed records; lights still to be packed.
    fn upload(gpu: &Arc<Gpu>, scene: &PreparedScene, p: PackedObjects, l: PackedLevels) -> GpuResult<GpuScene> {
        let none = vk::BufferUsageFlags::empty();
        let vertex_usage = vk::BufferUsageFlags::VERTEX_BUFFER;
        let super::beam_tables::PackedBeams { tables, receivers, items, beams } =
            super::beam_tables::pack_tables(scene, &p.beam_trees);
        let any_beams = beams.iter().any(Option::is_some);
        let beam_node_count = if any_beams { p.tree_nodes.len() } else { 1 };
        // The samples' entries, then the nodes' stand-ins.
        let beam_source_count = if any_beams { p.tree_order.len() + p.tree_nodes.len() } else { 1 };
        let t = super::transport_tables::pack(scene, &p.firsts, &l.levels);
        let zeros = vec![[0f32; 4]; p.vertices.len()];
        // The transport pass keeps each kernel vertex's dipole value, indexed like the exitance.
        let kernel_vertices = if t.objects.iter().any(Option::is_some) { p.vertices.len() } else { 0 };
        let sized = |name, item: usize, count: usize| storage(gpu, name, (item * count) as u64, none);
        // Made in the order they always were, vertices then indices first.
        let vertices = upload(gpu, "vertices", &p.vertices, vertex_usage)?;
        let indices = upload(gpu, "indices", &l.indices, vk::BufferUsageFlags::INDEX_BUFFER)?;
        Ok(GpuScene {
            buffers: SceneBuffers {
                vertices,
                // Opaque vertices keep zero exitance; translucent ones are written by the gather.
                exitance: upload(gpu, "exitance", &zeros, vertex_usage)?,
                environment_irradiance: upload(gpu, "environment irradiance", &zeros, vertex_usage)?,
                local_exitance: sized("local exitance", std::mem::size_of::<[f32; 4]>(), p.vertices.len())?,
                vertex_boundary: upload(gpu, "vertex boundary", &p.vertex_boundary, none)?,
                objects: upload(gpu, "objects", &p.objects, none)?,
                samples: upload(gpu, "samples", &p.samples, none)?,
                splat: sized("splat", std::mem::size_of::<SplatRecord>(), p.samples.len())?,
                splat_environment: sized("splat environment", std::mem::size_of::<[f32; 4]>(), p.samples.len())?,
                tree_nodes: upload(gpu, "tree nodes", &p.tree_nodes, none)?,
                tree_order: upload(gpu, "tree order", &p.tree_order, none)?,
                receiver_order: upload(gpu, "receiver order", &p.receiver_order, none)?,
                receiver_groups: upload(gpu, "receiver groups", &p.receiver_groups, none)?,
                group_items: upload(gpu, "group items", &p.group_items, none)?,
                blend_items: upload(gpu, "blend items", &p.blend_items, none)?,
                node_power: sized("node power", std::mem::size_of::<NodePowerRecord>(), p.tree_nodes.len())?,
                lights: sized("lights", std::mem::size_of::<LightGpu>(), scene.lights.len())?,
                level_vertices: upload(gpu, "level vertices", &l.level_vertices, none)?,
                texel_coords: upload(gpu, "texel coordinates", &p.texel_coords, none)?,
                texel_index: upload(gpu, "texel index", &p.texel_index, none)?,
                vertex_texel: upload(gpu, "vertex texel", &p.vertex_texel, none)?,
                texture_pyramid: sized("texture pyramid", std::mem::size_of::<f32>(), p.pyramid_nodes)?,
                bvh_nodes: upload(gpu, "caster hierarchy", &p.bvh_nodes, none)?,
                bvh_triangles: upload(gpu, "caster triangles", &p.bvh_triangles, none)?,
                beam_tables: upload(gpu, "beam tables", &tables, none)?,
                beam_nodes: sized("beam nodes", std::mem::size_of::<BeamNodeRecord>(), beam_node_count)?,
                beam_sources: sized("beam sources", std::mem::size_of::<BeamSourceRecord>(), beam_source_count)?,
                beam_norms: upload(gpu, "beam receivers", &receivers, none)?,
                beam_items: upload(gpu, "beam walk items", &items, none)?,
                transport_patches: upload(gpu, "transport patches", &t.patches, none)?,
                transport_items: upload(gpu, "transport items", &t.items, none)?,
                transport_matrix: upload(gpu, "transport matrix", &t.matrix, none)?,
                // Generation 0 in every F: none made under a visible-first frame's splat.
                transport_sums: upload(gpu, "transport sums", &vec![[0f32; 4]; 10 * t.patches.len().max(1)], none)?,
                transport_neighbours: upload(gpu, "transport neighbours", &t.neighbours, none)?,
                // Generation 0 everywhere: no patch needed, no dipole value current.
                transport_needed: upload(gpu, "transport needed", &vec![0u32; t.patches.len()], none)?,
                transport_dipole: upload(gpu, "transport dipole", &vec![[0f32; 4]; kernel_vertices], none)?,
                receiver_cones: upload(gpu, "receiver cones", &receiver_cones(scene, &l.levels), none)?,
                // Generation 0, which no gather marks: every receiver stale.
                receiver_state: upload(gpu, "receiver state", &vec![[0u32; 2]; p.vertices.len()], none)?,
            },
            indices,
            beams,
            beam_standins: p.tree_order.len() as u32,
            transport: t.objects,
            caster_triangles: p.bvh_triangles.len() as u32,
            ray_offset: scene.ray_offset() as f32,
            textures: p.textures,
            levels: l.levels,
            casters: l.casters,
            light_matrices: Vec::new(),
            receivers: p.receivers,
            coarser_receivers: p.coarser_receivers,
            node_heights: p.node_heights,
            vertex_count: p.vertices.len() as u32,
            sample_count: p.samples.len() as u32,
            light_count: scene.lights.len() as u32,
            key_light_count: crate::scene::lights::key_light_count(&scene.lights) as u32,
            key_lights_directional: crate::scene::lights::key_lights_directional(&scene.lights),
            pending_lights: None,
            object_records: p.objects,
            pending_objects: false,
        })
    }

    /// Pack the scene's lights and their shadow matrices (after a light moved; the number of
    /// lights and their shadow layers stay as they were). The records reach the GPU in the next
    /// recorded frame (`record_uploads`), so frames still in flight keep the lights they had.
    pub fn set_lights(&mut self, scene: &PreparedScene) {
        self.light_matrices = vec![[[0.0; 4]; 4]; scene.shadow_layers as usize];
        for l in &scene.lights {
            if let Some(layer) = l.shadow_layer {
                self.light_matrices[layer as usize] = l.shadow_matrix.to_cols_array_2d();
            }
        }
        self.pending_lights = Some(scene.lights.iter().map(LightGpu::new).collect());
        self.key_lights_directional = crate::scene::lights::key_lights_directional(&scene.lights);
    }

    /// Every object's vertex and sample range and index of refraction, in scene order, read from
    /// its record.
    pub fn object_ranges(&self) -> impl Iterator<Item = ObjectRange> + '_ {
        self.object_records.iter().map(|r| {
            let translucent = r.kind == super::records::MATERIAL_TRANSLUCENT;
            let [first_vertex, vertex_count, first_sample, sample_count] = r.ranges;
            let eta = if translucent { r.eta } else { 0.0 };
            ObjectRange { first_vertex, vertex_count, first_sample, sample_count, eta }
        })
    }

    /// Take the objects' levels of detail anew (`PreparedObject::levels` changed: an opaque
    /// object's levels baked from its sky light, `Renderer::bake_static_levels`): the index
    /// buffer is replaced. The translucent objects' levels, and so `level_vertices`, which the
    /// gathers' descriptor sets hold, must be as before. Call with no frame in flight.
    pub fn set_levels(&mut self, gpu: &Arc<Gpu>, scene: &PreparedScene) -> GpuResult<()> {
        let PackedLevels { indices, levels, casters, .. } = pack_levels(scene);
        self.indices = upload(gpu, "indices", &indices, vk::BufferUsageFlags::INDEX_BUFFER)?;
        self.levels = levels;
        self.casters = casters;
        Ok(())
    }

    /// Object `object` at level of detail `level`, or at its coarsest when it has fewer levels.
    pub fn level(&self, object: usize, level: usize) -> LevelRange {
        let levels = &self.levels[object];
        levels[level.min(levels.len() - 1)]
    }

    /// Where object `object`'s transport kernel lies at level of detail `level` (its coarsest
    /// where it has fewer), if it has one.
    pub fn transport_at(&self, object: usize, level: usize) -> Option<super::transport_tables::LevelTransport> {
        let levels = self.transport.get(object)?.as_ref()?;
        levels.get(level.min(levels.len().checked_sub(1)?)).copied()
    }

    /// Entry `j` of `receivers` at level of detail `level`: its `coarser_receivers` entry, or
    /// the whole mesh's where there is none (level 0, or a gather without coarser receivers).
    pub fn receiver_at(&self, j: usize, level: usize) -> &Receiver {
        match level.checked_sub(1).and_then(|l| self.coarser_receivers[j].get(l)) {
            Some(r) => r,
            None => &self.receivers[j],
        }
    }

    /// The scene's buffers, each also reachable by its `Resource` (`SceneBuffers::get`).
    pub fn buffers(&self) -> &SceneBuffers {
        &self.buffers
    }

    /// The scene's buffers, to write from the host (`Renderer::scene_data_mut` says when).
    pub fn buffers_mut(&mut self) -> &mut SceneBuffers {
        &mut self.buffers
    }

    /// Object `object`'s range (`object_ranges`).
    pub fn object_range(&self, object: usize) -> ObjectRange {
        self.object_ranges().nth(object).expect("an object of the scene")
    }

    /// Object `object`'s record as the next recorded frame uploads it.
    pub fn object_record(&self, object: usize) -> &ObjectRecord {
        &self.object_records[object]
    }

    /// Which channels of object `object` the last recorded plan computes locally (bit c:
    /// channel c), its record's `local_channels`.
    pub fn local_channels(&self, object: usize) -> u32 {
        self.object_records[object].local_channels
    }

    /// Set object `object`'s locally computed channels (bit c: channel c), uploaded by the next
    /// recorded frame when they changed.
    pub fn set_local_channels(&mut self, object: usize, mask: u32) {
        let record = &mut self.object_records[object];
        if record.local_channels != mask {
            record.local_channels = mask;
            self.pending_objects = true;
        }
    }

    /// Re-pack object `object`'s record from the scene (its material changed; its ranges and
    /// local channels stay), uploaded by the next recorded frame.
    pub fn set_material(&mut self, scene: &PreparedScene, object: usize) {
        let old = self.object_records[object];
        let mut record = ObjectRecord::new(&scene.objects[object], old.ranges);
        record.local_channels = old.local_channels;
        self.object_records[object] = record;
        self.pending_objects = true;
    }

    /// What the next `record_uploads` would write, to put back (`restore_uploads`) when the
    /// frame that recorded it is discarded unsubmitted.
    pub(in crate::render) fn uploads(&self) -> PendingUploads {
        PendingUploads {
            lights: self.pending_lights.clone(),
            objects: self.object_records.clone(),
            objects_pending: self.pending_objects,
        }
    }

    /// Put back what `uploads` returned: the next recorded frame uploads it again.
    pub(in crate::render) fn restore_uploads(&mut self, uploads: PendingUploads) {
        self.pending_lights = uploads.lights;
        self.object_records = uploads.objects;
        self.pending_objects = uploads.objects_pending;
    }

    /// The buffers the next `record_uploads` writes (by transfer): the lights and the object
    /// records, when they changed.
    pub fn pending_uploads(&self) -> Vec<Resource> {
        let lights = self.pending_lights.as_ref().is_some_and(|r| !r.is_empty());
        let mut pending = Vec::new();
        if lights {
            pending.push(Resource::Lights);
        }
        if self.pending_objects {
            pending.push(Resource::Objects);
        }
        pending
    }

    /// Record the copy of pending light and object records into their buffers
    /// (vkCmdUpdateBuffer, in the command buffer rather than through mapped memory, so frames in
    /// flight keep what they had). The barriers around it follow from `pending_uploads`.
    pub fn record_uploads(&mut self, device: &ash::Device, cmd: vk::CommandBuffer) {
        if let Some(records) = self.pending_lights.take().filter(|r| !r.is_empty()) {
            update(device, cmd, &self.buffers.lights, bytemuck::cast_slice(&records));
        }
        if std::mem::take(&mut self.pending_objects) {
            update(device, cmd, &self.buffers.objects, bytemuck::cast_slice(&self.object_records));
        }
    }
}

/// vkCmdUpdateBuffer of `bytes` at the start of `buffer`, in the 65536-byte pieces it takes.
fn update(device: &ash::Device, cmd: vk::CommandBuffer, buffer: &Buffer, bytes: &[u8]) {
    for (i, chunk) in bytes.chunks(65536).enumerate() {
        // SAFETY: `cmd` is recording outside rendering; the range lies inside the buffer, which
        // has TRANSFER_DST usage; sizes are multiples of 4 (records are multiples of 16 bytes).
        unsafe { device.cmd_update_buffer(cmd, buffer.raw(), (i * 65536) as u64, chunk) };
    }
}
