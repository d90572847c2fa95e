// SD-tree as flat arrays (path guiding). The CPU refits these between passes.
#ifndef LANTERNA_GUIDING_H
#define LANTERNA_GUIDING_H

#define GUIDE_FLAG_RECORD_NEE 1u
#define GUIDE_FLAG_SPATIAL_JITTER 2u
#define GUIDE_FLAG_DIRECTIONAL_BOX 4u

// Spatial binary tree node. Leaves have axis == 3 and `child` = leaf index.
struct GuideSpatialNode {
    uint axis;
    uint child;      // interior: index of the first child (the second is child + 1)
};

// Per spatial leaf: where its quadtrees start, and its box.
struct GuideLeaf {
    uint sampling_root;   // node index in the sampling quadtree array
    uint training_root;   // node index in the training quadtree array
    vec3 box_min;
    vec3 box_size;
};

// Directional quadtree node over ((cosθ+1)/2, φ/2π): four child sums and children
// (0 = the child is a leaf). Child order: 0 = (lo u, lo v), 1 = (hi u, lo v),
// 2 = (lo u, hi v), 3 = (hi u, hi v).
struct GuideQuadNode {
    vec4 sum;
    uvec4 child;
};

#endif
