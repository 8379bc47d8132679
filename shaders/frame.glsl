// Per-frame parameters, shared by every stage (set 0, binding 0). Must match `FrameUniforms` in src/render/mod.rs.
layout(std140, set = 0, binding = 0) uniform Frame {
    mat4 tex_to_clip;   // texture space [0,1]^3 -> Vulkan clip space (y down)
    mat4 clip_to_tex;   // its inverse: unprojects pixels for near-plane points and analytic rays
    vec4 eye_tex;       // xyz: the eye in texture space
    vec4 slab_lo;       // xyz: slab box, texture space
    vec4 slab_hi;
    vec4 extent;        // xyz: world size of the box; w: step length in world units
    vec4 value_map;     // x, y: sampled -> normalised value (v = s * x + y); z, w: value window
    vec4 alpha;         // x: step alpha; y: step length in voxels; z: early termination; w: 1 = multiplied alpha
    vec4 background;    // rgb
    vec4 viewport;      // x, y: target size in pixels; z: most samples a ray may take
} frame;
