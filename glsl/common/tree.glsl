// Walks of an object's sample hierarchy (sampling::SampleTree; glsl/common/scene.glsl's
// TreeNodeRecord), stackless: nodes are depth first, a node's first child is the next node and
// range_skip.z is where the walk goes once its subtree is done.
//
// Include after scene.glsl, and after declaring the buffers tree_nodes[] (TreeNodeRecord),
// tree_order[] (uint) and samples[] (SampleRecord).
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

#endif
