// Any-hit shadow rays against the shadow casters' bounding-volume hierarchy, the f32 twin of
// reference::bvh::Bvh::occluded (same nodes, boxes rounded outward; Moller-Trumbore 1997 at each
// leaf's triangles). Declares the two buffers it reads in set 0 at the bindings the includer
// defines first, RAYS_NODES_BINDING and RAYS_TRIANGLES_BINDING (records::BvhNodeRecord,
// records::BvhTriangleRecord).
#ifndef RAYS_GLSL
#define RAYS_GLSL
struct BvhNode {
    vec4 min_first;  // xyz: lower corner; w: bits of a leaf's first triangle / an inner node's left child
    vec4 max_count;  // xyz: upper corner; w: bits of a leaf's triangle count (0: inner node)
};
struct BvhTriangle {
    vec4 a, b, c;
};
layout(std430, set = 0, binding = RAYS_NODES_BINDING) readonly buffer BvhNodes { BvhNode bvh_nodes[]; };
layout(std430, set = 0, binding = RAYS_TRIANGLES_BINDING) readonly buffer BvhTriangles { BvhTriangle bvh_triangles[]; };

// Slab test: does origin + t dir, t in [0, t_max], touch the box? `inv` is 1 / dir.
bool ray_box(vec3 lo, vec3 hi, vec3 origin, vec3 inv, float t_max) {
    vec3 t0 = (lo - origin) * inv, t1 = (hi - origin) * inv;
    vec3 tn = min(t0, t1), tf = max(t0, t1);
    float near = max(max(max(tn.x, tn.y), tn.z), 0.0);
    float far = min(min(min(tf.x, tf.y), tf.z), t_max);
    return near <= far;
}

// Does origin + t dir meet the triangle for t in (t_min, t_max)?
bool ray_triangle(BvhTriangle tri, vec3 origin, vec3 dir, float t_min, float t_max) {
    vec3 e1 = tri.b.xyz - tri.a.xyz, e2 = tri.c.xyz - tri.a.xyz;
    vec3 p = cross(dir, e2);
    float det = dot(e1, p);
    if (abs(det) < 1e-30) return false;
    float inv = 1.0 / det;
    vec3 s = origin - tri.a.xyz;
    float u = dot(s, p) * inv;
    vec3 q = cross(s, e1);
    float v = dot(dir, q) * inv;
    float t = dot(e2, q) * inv;
    return u >= 0.0 && u <= 1.0 && v >= 0.0 && u + v <= 1.0 && t > t_min && t < t_max;
}

// Is anything of the hierarchy hit along origin + t dir, t in (t_min, t_max)? A stack of 32
// holds any walk: median splits halve the triangles at each level.
bool ray_occluded(vec3 origin, vec3 dir, float t_min, float t_max) {
    vec3 inv = 1.0 / dir;
    uint stack[32];
    int top = 0;
    uint node = 0u;
    while (true) {
        BvhNode n = bvh_nodes[node];
        if (ray_box(n.min_first.xyz, n.max_count.xyz, origin, inv, t_max)) {
            uint first = floatBitsToUint(n.min_first.w), count = floatBitsToUint(n.max_count.w);
            if (count == 0u) {
                if (top < 32) stack[top++] = first + 1u;
                node = first;
                continue;
            }
            for (uint t = first; t < first + count; ++t) {
                if (ray_triangle(bvh_triangles[t], origin, dir, t_min, t_max)) return true;
            }
        }
        if (top == 0) return false;
        node = stack[--top];
    }
    return false;
}
#endif
