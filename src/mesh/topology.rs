//! Edge adjacency, boundary detection and vertex one-rings.
//!
//! Edges are found by sorting (vertex, vertex, triangle corner) records rather than through a hash
//! map: it is deterministic and allocation-light, and O(F log F) for F triangles.

use super::NO_NEIGHBOUR;

pub(super) struct Topology {
    pub neighbours: Vec<[u32; 3]>,
    /// The edges used by exactly one triangle (low vertex, high vertex).
    pub boundary_edges: Vec<[u32; 2]>,
    pub non_manifold_edges: usize,
    pub inconsistent_edges: usize,
    pub boundary_vertex: Vec<bool>,
    pub ring_offsets: Vec<u32>,
    pub ring: Vec<u32>,
}

pub(super) fn build(vertex_count: usize, triangles: &[[u32; 3]]) -> Topology {
    // (low vertex, high vertex, triangle * 3 + edge): edge e runs from corner e to corner e + 1.
    let mut edges: Vec<(u32, u32, u32)> = Vec::with_capacity(triangles.len() * 3);
    for (t, tri) in triangles.iter().enumerate() {
        for e in 0..3 {
            let (a, b) = (tri[e], tri[(e + 1) % 3]);
            edges.push((a.min(b), a.max(b), (t * 3 + e) as u32));
        }
    }
    edges.sort_unstable();

    let mut neighbours = vec![[NO_NEIGHBOUR; 3]; triangles.len()];
    let mut boundary_vertex = vec![false; vertex_count];
    let mut boundary_edges = Vec::new();
    let (mut non_manifold_edges, mut inconsistent_edges) = (0, 0);
    let mut ring_counts = vec![0u32; vertex_count + 1];

    let mut start = 0;
    while start < edges.len() {
        let (a, b, _) = edges[start];
        let mut end = start + 1;
        while end < edges.len() && edges[end].0 == a && edges[end].1 == b {
            end += 1;
        }
        ring_counts[a as usize] += 1;
        ring_counts[b as usize] += 1;
        match end - start {
            2 => {
                let (c0, c1) = (edges[start].2, edges[start + 1].2);
                let (t0, e0, t1, e1) = (c0 / 3, c0 % 3, c1 / 3, c1 % 3);
                neighbours[t0 as usize][e0 as usize] = t1;
                neighbours[t1 as usize][e1 as usize] = t0;
                // Consistent winding traverses a shared edge in opposite directions.
                let from0 = triangles[t0 as usize][e0 as usize];
                let from1 = triangles[t1 as usize][e1 as usize];
                if from0 == from1 {
                    inconsistent_edges += 1;
                }
            }
            count => {
                if count == 1 {
                    boundary_edges.push([a, b]);
                } else {
                    non_manifold_edges += 1;
                }
                boundary_vertex[a as usize] = true;
                boundary_vertex[b as usize] = true;
            }
        }
        start = end;
    }

    // One-rings in CSR form, from the unique edges (already sorted, so each ring comes out sorted
    // after the two passes below).
    let mut ring_offsets = vec![0u32; vertex_count + 1];
    for v in 0..vertex_count {
        ring_offsets[v + 1] = ring_offsets[v] + ring_counts[v];
    }
    let mut fill = ring_offsets.clone();
    let mut ring = vec![0u32; ring_offsets[vertex_count] as usize];
    let mut last = None;
    for &(a, b, _) in &edges {
        if last == Some((a, b)) {
            continue;
        }
        last = Some((a, b));
        ring[fill[a as usize] as usize] = b;
        fill[a as usize] += 1;
        ring[fill[b as usize] as usize] = a;
        fill[b as usize] += 1;
    }
    for v in 0..vertex_count {
        ring[ring_offsets[v] as usize..ring_offsets[v + 1] as usize].sort_unstable();
    }

    Topology { neighbours, boundary_edges, non_manifold_edges, inconsistent_edges, boundary_vertex, ring_offsets, ring }
}
