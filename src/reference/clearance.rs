//! A lower bound of the distance to a mesh's surface anywhere in its bounding box, from a grid:
//! what lets the radiative-transfer walk (`reference::rte_mesh`) skip the BVH's closest-hit
//! query for a flight that cannot reach the surface.
//!
//! The distance to a set is 1-Lipschitz, so at any point of a cubic cell it is at least the
//! distance at the cell's centre less half the cell's diagonal. Each cell stores that bound
//! (less a margin for rounding), computed once per object with [`Bvh::distance`]; a flight from
//! `p` shorter than the bound of `p`'s cell meets no triangle, which is exactly what the query
//! would have answered. Deep inside a marble sphere (a mean free path of 0.46 mm in a radius of
//! 10 mm) most flights are such: the query was three quarters of the walk's time.
//!
//! Near the surface a cell also lists the triangles a flight of at most [`REACH`] cells from it
//! can meet (those within the reach and half the diagonal of its centre): such a flight is
//! tested against them alone, not the whole BVH, which there still took half the walk's time.

use super::bvh::Bvh;
use glam::DVec3;
use rayon::prelude::*;

/// Cells along the bounding box's longest side, for a mesh of up to [`DENSE`] triangles.
const CELLS: f64 = 64.0;
/// The triangles above which the grid gets finer ([`cells_for`]).
const DENSE: f64 = 20_000.0;
/// The finest grid: 128³ cells, 16 MiB of bounds and list starts.
const MAX_CELLS: f64 = 128.0;
/// The longest flight, in cells' sides, tested against a cell's list (longer ones ask the
/// BVH): three sides are two mean free paths of marble's red on the 2 cm sphere.
const REACH: f64 = 3.0;

/// Cells along the bounding box's longest side for a mesh of `triangles` triangles: [`CELLS`],
/// finer as the cube root of the triangles past [`DENSE`]. On a dense mesh a cell near the
/// surface lists many triangles, each tested by every flight from it; a finer grid shortens the
/// lists but sends more flights past its reach to the BVH. Measured on the transport kernel's
/// walk (`examples/transport_kernel.rs`, 600,000 walks per channel, lavapipe's 2-core VM): the
/// built-in bunny (75,408 triangles) took 61.3 s at 64 cells, 34.7 s at 89, 31.7 s at 96 and
/// 29.9 s at this rule's 100; the 2 cm marble sphere (2,208) 5.5 to 5.8 s at 48 and 64 cells,
/// 6.7 to 6.9 s at 96. The walk is the same at any resolution: only which test answers changes.
fn cells_for(triangles: usize) -> f64 {
    (CELLS * (triangles as f64 / DENSE).cbrt()).clamp(CELLS, MAX_CELLS)
}

/// What a flight from a point may meet ([`Clearance::flight`]).
pub enum Flight<'a> {
    /// Nothing: the surface is farther than the flight.
    Clear,
    /// At most these triangles (indices into the BVH's list).
    Near(&'a [u32]),
    /// Anything: ask the BVH.
    Far,
}

/// The bound on a grid of cubic cells over a bounding box.
pub struct Clearance {
    /// The grid's lowest corner.
    min: DVec3,
    /// One over the cells' side.
    inv_side: f64,
    /// Cells per axis.
    dims: [usize; 3],
    /// Per cell (x fastest): the lower bound, never negative.
    bound: Vec<f32>,
    /// The longest flight a cell's list serves.
    reach: f64,
    /// Per cell, where its list starts in `near` (one more entry: the end of the last).
    start: Vec<u32>,
    /// The cells' lists, one after the other.
    near: Vec<u32>,
}

impl Clearance {
    /// The grid over the box `min..max` of the triangles in `bvh`.
    pub fn new(bvh: &Bvh, min: DVec3, max: DVec3) -> Clearance {
        let extent = (max - min).max(DVec3::splat(1e-300));
        let side = extent.max_element() / cells_for(bvh.triangle_count());
        let dims = [0, 1, 2].map(|k| ((extent[k] / side).ceil() as usize).max(1));
        let half_diagonal = 0.5 * side * 3f64.sqrt();
        // Rounding: the hit test's and the f32's, far below a cell.
        let margin = 1e-6 * side + 1e-9 * extent.max_element();
        let reach = REACH * side;
        let cells: Vec<(f32, Vec<u32>)> = (0..dims[0] * dims[1] * dims[2])
            .into_par_iter()
            .map(|i| {
                let cell =
                    DVec3::new((i % dims[0]) as f64, (i / dims[0] % dims[1]) as f64, (i / dims[0] / dims[1]) as f64);
                let centre = min + (cell + 0.5) * side;
                let bound = (bvh.distance(centre) - half_diagonal - margin).max(0.0);
                let mut near = Vec::new();
                if bound <= reach {
                    bvh.within(centre, reach + half_diagonal + margin, &mut near);
                }
                // Shrunk by a millionth first, so that rounding to f32 cannot raise it.
                ((bound * (1.0 - 1e-6)) as f32, near)
            })
            .collect();
        let mut start = Vec::with_capacity(cells.len() + 1);
        let mut near = Vec::new();
        for (_, list) in &cells {
            start.push(near.len() as u32);
            near.extend_from_slice(list);
        }
        start.push(near.len() as u32);
        let bound = cells.into_iter().map(|(b, _)| b).collect();
        Clearance { min, inv_side: 1.0 / side, dims, bound, reach, start, near }
    }

    /// What a flight of length `s` from `p` may meet.
    pub fn flight(&self, p: DVec3, s: f64) -> Flight<'_> {
        let Some(i) = self.cell(p) else { return Flight::Far };
        if s < f64::from(self.bound[i]) {
            Flight::Clear
        } else if s <= self.reach && self.start[i] < self.start[i + 1] {
            Flight::Near(&self.near[self.start[i] as usize..self.start[i + 1] as usize])
        } else {
            Flight::Far
        }
    }

    /// The index of the cell that holds `p`, if one does.
    fn cell(&self, p: DVec3) -> Option<usize> {
        let q = (p - self.min) * self.inv_side;
        let (x, y, z) = (q.x.floor(), q.y.floor(), q.z.floor());
        let [nx, ny, nz] = self.dims;
        // Also false for NaN.
        let inside = x >= 0.0 && y >= 0.0 && z >= 0.0 && x < nx as f64 && y < ny as f64 && z < nz as f64;
        inside.then(|| x as usize + nx * (y as usize + ny * z as usize))
    }

    /// A lower bound of the distance from `p` to the surface (0 outside the grid).
    pub fn at(&self, p: DVec3) -> f64 {
        self.cell(p).map_or(0.0, |i| f64::from(self.bound[i]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bound_never_exceeds_the_distance_and_is_useful_deep_inside() {
        // An octahedron of radius 1: the distance inside is (1 - |x| - |y| - |z|) / sqrt(3).
        let v = [DVec3::X, -DVec3::X, DVec3::Y, -DVec3::Y, DVec3::Z, -DVec3::Z];
        let mut tris = Vec::new();
        for &x in &v[0..2] {
            for &y in &v[2..4] {
                for &z in &v[4..6] {
                    tris.push([x, y, z]);
                }
            }
        }
        let bvh = Bvh::new(tris);
        let grid = Clearance::new(&bvh, -DVec3::ONE, DVec3::ONE);
        let mut state = 7u64;
        let mut rnd = move || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..20_000 {
            let p = DVec3::new(rnd(), rnd(), rnd()) * 2.4 - 1.2;
            let exact = bvh.distance(p);
            assert!(grid.at(p) <= exact, "at {p}: bound {} above the distance {exact}", grid.at(p));
        }
        // At the centre the distance is 1 / sqrt(3); the bound is within a cell's diagonal.
        let side = 2.0 / CELLS;
        assert!(grid.at(DVec3::splat(1e-3)) > 1.0 / 3f64.sqrt() - 2.0 * side * 3f64.sqrt());
        assert_eq!(grid.at(DVec3::splat(5.0)), 0.0);
        // Every triangle a flight within the reach meets is on its cell's list.
        let (mut listed, mut hits) = (0, 0);
        for _ in 0..20_000 {
            let p = DVec3::new(rnd(), rnd(), rnd()) * 1.2 - 0.6;
            let d = (DVec3::new(rnd(), rnd(), rnd()) - 0.5).normalize();
            let s = rnd() * grid.reach;
            if let Flight::Near(list) = grid.flight(p, s) {
                listed += 1;
                for t in 0..8 {
                    if crate::reference::bvh::intersect_uv(bvh.triangle(t), p, d)
                        .is_some_and(|(h, ..)| h > 0.0 && h < s)
                    {
                        hits += 1;
                        assert!(list.contains(&(t as u32)), "flight {s} from {p} along {d} meets {t}, not listed");
                    }
                }
            }
        }
        assert!(listed > 1000 && hits > 100, "the test must exercise the lists ({listed} flights, {hits} hits)");
    }
}

#[cfg(test)]
mod dense_tests {
    use super::*;

    /// The octahedron of radius 1 with each face cut into `4^k` (flat: the distance test needs
    /// no sphere).
    fn subdivided_octahedron(k: u32) -> Vec<[DVec3; 3]> {
        let v = [DVec3::X, -DVec3::X, DVec3::Y, -DVec3::Y, DVec3::Z, -DVec3::Z];
        let mut tris: Vec<[DVec3; 3]> = (0..8).map(|i| [v[i & 1], v[2 + (i >> 1 & 1)], v[4 + (i >> 2 & 1)]]).collect();
        for _ in 0..k {
            tris = tris
                .iter()
                .flat_map(|&[a, b, c]| {
                    let (ab, bc, ca) = ((a + b) / 2.0, (b + c) / 2.0, (c + a) / 2.0);
                    [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]
                })
                .collect();
        }
        tris
    }

    /// A dense mesh gets a finer grid, at most [`MAX_CELLS`], and the finer grid keeps both
    /// promises: its bound is never above the distance, and the closest triangle a flight
    /// within the reach meets is on its cell's list.
    #[test]
    fn a_dense_mesh_gets_a_finer_grid_that_still_bounds_the_distance_and_lists_every_hit() {
        assert_eq!(cells_for(2_208), CELLS);
        assert!((99.0..101.0).contains(&cells_for(75_408)), "{}", cells_for(75_408));
        assert_eq!(cells_for(10_000_000), MAX_CELLS);
        let bvh = Bvh::new(subdivided_octahedron(6));
        assert_eq!(bvh.triangle_count(), 32_768);
        let grid = Clearance::new(&bvh, -DVec3::ONE, DVec3::ONE);
        assert!(grid.dims[0] > CELLS as usize, "{:?}", grid.dims);
        let mut state = 11u64;
        let mut rnd = move || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut listed, mut hits) = (0, 0);
        for _ in 0..20_000 {
            let p = DVec3::new(rnd(), rnd(), rnd()) * 1.2 - 0.6;
            assert!(grid.at(p) <= bvh.distance(p), "at {p}: bound {} above the distance", grid.at(p));
            let d = (DVec3::new(rnd(), rnd(), rnd()) - 0.5).normalize();
            let s = rnd() * grid.reach;
            if let Flight::Near(list) = grid.flight(p, s) {
                listed += 1;
                if let Some(hit) = bvh.closest_hit(p, d, 0.0, s, None) {
                    hits += 1;
                    assert!(list.contains(&(hit.triangle as u32)), "flight {s} from {p} along {d}: {hit:?} not listed");
                }
            }
        }
        assert!(listed > 1000 && hits > 100, "the test must exercise the lists ({listed} flights, {hits} hits)");
    }
}
