// Per-frame parameters, shared by every stage (set 0, binding 0). Must match `FrameUniforms` in src/render/mod.rs.
layout(std140, set = 0, binding = 0) uniform Frame {
    mat4 tex_to_clip;   // texture space [0,1]^3 -> Vulkan clip space (y down)
    vec4 eye_tex;       // xyz: the eye in texture space
    // A pixel's ray direction in texture space is ray_forward + ndc.x * ray_right + ndc.y * ray_down, scaled so
    // that its component along the view axis is one world unit: the near plane is at t = ray_forward.w.
    // (Built from the camera's basis rather than an inverse projection, which loses precision in f32.)
    vec4 ray_forward;
    vec4 ray_right;
    vec4 ray_down;
    vec4 slab_lo;       // xyz: slab box, texture space
    vec4 slab_hi;
    vec4 extent;        // xyz: world size of the box; w: step length in world units
    vec4 value_map;     // x, y: sampled -> normalised value (v = s * x + y); z, w: value window
    vec4 alpha;         // x: step alpha; y: step length in voxels; z: early termination; w: 1 = multiplied alpha
    vec4 background;    // rgb
    vec4 viewport;      // x, y: target size in pixels; z: most samples a ray may take
} frame;
