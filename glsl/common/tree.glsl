// Traversals of an object's sample hierarchy (sampling::SampleTree; glsl/common/scene.glsl's
// TreeNodeRecord), stackless: nodes are depth first, a node's first child is the next node and
// range_skip.z is where the walk goes once its subtree is done. The f64 twins are in
// src/reference/tree.rs.
//
// Include after dipole.glsl, scene.glsl and gather.glsl, and after declaring the buffers
// tree_nodes[] (TreeNodeRecord), tree_order[] (uint), samples[] (SampleRecord) and, for
// tree_gather, node_power[] (NodePowerRecord) and splat[] (SplatRecord).
#ifndef TREE_GLSL
#define TREE_GLSL

// A lower bound on the distance from x to any sample of the node (negative inside its sphere).
float tree_node_distance(TreeNodeRecord n, vec3 x) {
    return distance(x, n.center_radius.xyz) - n.center_radius.w;
}

// The sample of the tree nearest to x (the near blend's fallback where no Shepard weight reaches).
uint tree_nearest_sample(vec3 x, uint first_node, uint node_count) {
    uint best = 0u;
    float best_sq = 3.4e38;
    uint i = first_node, end = first_node + node_count;
    while (i < end) {
        TreeNodeRecord n = tree_nodes[i];
        float dist = tree_node_distance(n, x);
        if (dist > 0.0 && dist * dist >= best_sq) {
            i = n.range_skip.z;
        } else if (n.range_skip.w != 0u) {
            for (uint k = n.range_skip.x; k < n.range_skip.x + n.range_skip.y; ++k) {
                uint s = tree_order[k];
                vec3 d = x - samples[s].position_area.xyz;
                float r_sq = dot(d, d);
                if (r_sq < best_sq || (r_sq == best_sq && s < best)) {
                    best_sq = r_sq;
                    best = s;
                }
            }
            i = n.range_skip.z;
        } else {
            i += 1u;
        }
    }
    return best;
}

#ifdef TREE_GATHER
// The hierarchical dipole sum at x (after Jensen and Buhler 2002), walked once for a group of
// receivers inside the sphere (group_center, group_radius): dist, the nearest any sample of a
// node can be to any receiver of the group, decides for all of them (sampling::ReceiverGroups
// says why). A node whose samples are all beyond every near-blend radius and whose area A is
// below the solid-angle bound, A < epsilon dist^2, acts as one sample: its power at its
// power-weighted centroid with the far kernel of its mean area. Leaves are summed sample by
// sample with the flat gather's gather_add, so the near field and its blend are exact. A node
// that could add at most DIPOLE_TREE_PRUNE_FRACTION of the object's mean exitance in every
// channel (R_d,total times its power per area; R_d at dist bounds R_far beyond) is skipped.
// epsilon = 0 uses no node whole and prunes none: the flat sum.
GatherSum tree_gather(vec3 x, vec3 group_center, float group_radius, DipoleChannel ch[3], uint first_node,
                      uint node_count, float epsilon) {
    GatherSum g = gather_begin();
    if (node_count == 0u) return g;
    // The prune threshold per channel, from the root's aggregate.
    NodePowerRecord root = node_power[first_node];
    float root_area = max(tree_nodes[first_node].area_reach.x, 1e-30);
    vec3 negligible;
    for (int c = 0; c < 3; ++c) {
        // epsilon = 0 prunes nothing either: the exact flat sum.
        negligible[c] = epsilon > 0.0 ? DIPOLE_TREE_PRUNE_FRACTION * dipole_r_d_total(ch[c]) * root.power[c] / root_area
                                      : -1.0;
    }
    uint i = first_node, end = first_node + node_count;
    while (i < end) {
        TreeNodeRecord n = tree_nodes[i];
        float dist = distance(group_center, n.center_radius.xyz) - n.center_radius.w - group_radius;
        bool beyond_blend = dist > n.area_reach.y;
        if (beyond_blend && n.area_reach.x < epsilon * dist * dist) {
            NodePowerRecord p = node_power[i];
            vec3 d = x - p.mean_weight.xyz;
            float beta = DIPOLE_B_PER_SQRT_AREA * DIPOLE_B_PER_SQRT_AREA * n.area_reach.z;
            for (int c = 0; c < 3; ++c) {
                g.partial[c] += p.power[c] * dipole_r_d_far_sq(ch[c], dot(d, d), beta);
            }
            i = n.range_skip.z;
        } else if (n.range_skip.w != 0u) {
            for (uint k = n.range_skip.x; k < n.range_skip.x + n.range_skip.y; ++k) {
                uint s = tree_order[k];
                gather_add(g, ch, x, samples[s].position_area, splat[s].irradiance_area.rgb, splat[s].near_energy.rgb);
            }
            gather_flush(g);
            i = n.range_skip.z;
        } else {
            bool negligible_node = beyond_blend;
            if (beyond_blend) {
                vec3 power = node_power[i].power.rgb;
                for (int c = 0; c < 3; ++c) {
                    negligible_node = negligible_node && power[c] * dipole_r_d(ch[c], dist) <= negligible[c];
                }
            }
            i = negligible_node ? n.range_skip.z : i + 1u;
        }
    }
    gather_flush(g);
    if (g.weight_sum == 0.0) {
        // No Shepard weight reached x: the nearest sample's near exitance, found anywhere in
        // the tree (a node used whole may hold it).
        uint s = tree_nearest_sample(x, first_node, node_count);
        g.nearest_near = splat[s].irradiance_area.rgb * splat[s].near_energy.rgb;
    }
    return g;
}
#endif

#endif
