// Per-frame parameters, shared by every stage (set 0, binding 0). Must match `FrameUniforms` in src/render/uniforms.rs.
layout(std140, set = 0, binding = 0) uniform Frame {
    mat4 tex_to_clip;     // texture space [0,1]^3 -> Vulkan clip space (y down)
    mat4 tex_to_world;    // texture space -> the render world (RenderSettings rule 1): its linear part measures rays
    mat4 gradient_to_world; // a gradient per voxel (index space) -> along the world normal
    vec4 eye_tex;         // xyz: the eye in texture space
    // Pixel ray, texture space, for ndc in [-1,1]^2 (y down): origin = eye_tex + ndc.x * origin_dx + ndc.y * origin_dy
    // (orthographic) and direction = ray_forward + ndc.x * ray_right + ndc.y * ray_down (perspective), scaled so
    // the direction's component along the view axis is one world unit: the near plane is at t = ray_forward.w.
    // (Built from the camera's basis rather than an inverse projection, which loses precision in f32.)
    vec4 ray_forward;
    vec4 ray_right;
    vec4 ray_down;
    vec4 origin_dx;
    vec4 origin_dy;
    vec4 slab_lo;         // xyz: slab box, texture space
    vec4 slab_hi;
    vec4 extent;          // w: step length in world units
    vec4 value_map;       // x, y: sampled -> normalised value (v = s * x + y); z, w: value window
    vec4 alpha;           // y: step length in voxels; z: early termination
    vec4 background;      // rgb: linear light
    vec4 viewport;        // x, y: target size in pixels; z: most samples a ray may take; w: 1 = output samples taken
    vec4 texel;           // xyz: 1 / dims (one voxel in texture space)
    vec4 voxel_world;     // x: rule 5's shading fade width (0: off); y, z: rule 13's overlays and label maps; w: gradient-opacity reference (0: off)
    vec4 shading;         // ambient, diffuse, specular, shininess
    vec4 mode_params;     // x: iso value; y: density factor; z: 1 = look up bricks (skip, stride); w: iso-surfaces
    uvec4 flags;          // x: composite mode (CompositeMode::index); y: jitter on; z: jitter seed; w: shading on
    vec4 brick;           // xyz: a brick's size in texture space (8 / dims)
    vec4 dims;            // xyz: the volume's size in voxels
    vec4 iso_values;      // rule 7's surfaces, by value (mode_params.w of them)
    vec4 iso_colors[4];   // per surface: linear rgb (r < 0: the classification's colour) and opacity
    vec4 light_dir;       // xyz: unit direction towards the light (world); w: 1 directional, 0 headlight
    vec4 light_color;     // rgb: linear colour x intensity
    vec4 light_grid;      // rule 9: xyz the shadow read's offset towards the light (texture space); w: 1 shadows + 2 occlusion
    vec4 clip_plane;      // rule 10, texture space: p is kept where dot(xyz, p) + w >= 0 (0,0,0,1 keeps everything)
    vec4 pool_inv;        // xyz: 1 / the brick pool's size in texels (render/pool.rs)
    vec4 pool_brick;      // xyz: a brick's size in voxels of its level; w: the border in voxels
    vec4 pool_slot;       // xyz: a slot's size in texels
    vec4 pool_grid;       // xyz: level-0 bricks per axis (the page table's size); w: the step's level (rule 2)
    // Rule 11, a rank's share of each ray (src/distributed): xyz the voxel of the whole volume where this process's
    // texture starts (0 for a whole volume); w: 1 = write the share's premultiplied partial output (march.glsl).
    vec4 part_origin;
    vec4 part_lo;         // xyz: the box this process owns (texture space of the whole; -1e30/1e30 open sides)
    vec4 part_hi;
} frame;
