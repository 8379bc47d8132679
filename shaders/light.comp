#version 450
// Rule 9's light grid (RenderSettings docs; src/render/light_volume.rs records the passes): x the light's
// transmittance T, y the ambient occlusion O. Pass 0 fills every cell with (1, O) (O = 1 without occlusion); each
// later pass is one slice of the shadow sweep, from the slice nearest the light on, reading the slice before it.
#include "frame.glsl"
#include "volume.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(set = 2, binding = 0, rgba16f) uniform image3D light_img;
// Extinction per voxel length at 4096 values (light_volume::extinction_table).
layout(std430, set = 2, binding = 1) readonly buffer Extinction {
    float sigma[4096];
} ext;

layout(push_constant) uniform Pass {
    // x: 0 occlusion/fill, 1 a shadow slice; y: the slice's index along the sweep axis; z: the sweep axis; w: 1 =
    // occlusion on (pass 0), 1 = the first slice (pass 1).
    ivec4 info;
    // xyz: the step towards the light in cells; w: its world length in voxels.
    vec4 delta;
    // xyz: the grid's size in cells; w: one voxel (the smallest side) in world units.
    vec4 grid;
} pc;

float extinction(float v) {
    if (isnan(v)) {
        return 0.0;
    }
    float u = clamp(v, 0.0, 1.0) * 4095.0;
    int i0 = min(int(u), 4094);
    return mix(ext.sigma[i0], ext.sigma[i0 + 1], u - float(i0));
}

// Rule 3's value at cell position c (cell units, centres at integers).
float value_at_cell(vec3 c) {
    return sample_value((c + 0.5) / pc.grid.xyz);
}

// World length of a step of `u` cells, in voxels.
float cells_to_voxels(vec3 u) {
    return length(mat3(frame.tex_to_world) * (u / pc.grid.xyz)) / pc.grid.w;
}

float occlusion(vec3 c) {
    float sum = 0.0;
    for (int i = 0; i < 14; i++) {
        vec3 u;
        if (i < 6) {
            u = vec3(0.0);
            u[i >> 1] = (i & 1) == 0 ? 1.0 : -1.0;
        } else {
            int j = i - 6;
            u = vec3((j & 1) == 0 ? 1.0 : -1.0, (j & 2) == 0 ? 1.0 : -1.0, (j & 4) == 0 ? 1.0 : -1.0) / sqrt(3.0);
        }
        float ell = cells_to_voxels(u);
        float tau = 0.0;
        for (int k = 1; k <= 4; k++) {
            vec3 q = c + float(k) * u;
            bool inside = all(greaterThanEqual(q, vec3(-0.5))) && all(lessThanEqual(q, pc.grid.xyz - 0.5));
            tau += inside ? extinction(value_at_cell(q)) * ell : 0.0;
        }
        sum += exp(-tau);
    }
    return sum / 14.0;
}

// T of the previous slice at cell position q (its index along the sweep axis is whole), bilinear over the other
// two axes, cells beyond the grid reading 1.
float previous_t(vec3 q, int axis, int o1, int o2) {
    ivec3 n = ivec3(pc.grid.xyz);
    int i0 = int(floor(q[o1]));
    int j0 = int(floor(q[o2]));
    float fx = q[o1] - float(i0);
    float fy = q[o2] - float(j0);
    float t[4];
    for (int k = 0; k < 4; k++) {
        ivec3 c;
        c[axis] = int(round(q[axis]));
        c[o1] = i0 + (k & 1);
        c[o2] = j0 + (k >> 1);
        bool inside = c[o1] >= 0 && c[o1] < n[o1] && c[o2] >= 0 && c[o2] < n[o2];
        t[k] = inside ? imageLoad(light_img, c).x : 1.0;
    }
    return mix(mix(t[0], t[1], fx), mix(t[2], t[3], fx), fy);
}

void main() {
    ivec3 n = ivec3(pc.grid.xyz);
    if (pc.info.x == 0) {
        ivec3 c = ivec3(gl_GlobalInvocationID.xy, gl_WorkGroupID.z);
        if (c.x >= n.x || c.y >= n.y) {
            return;
        }
        float o = pc.info.w != 0 ? occlusion(vec3(c)) : 1.0;
        imageStore(light_img, c, vec4(1.0, o, 0.0, 0.0));
        return;
    }
    int axis = pc.info.z;
    int o1 = axis == 0 ? 1 : 0;
    int o2 = axis == 2 ? 1 : 2;
    ivec3 c;
    c[axis] = pc.info.y;
    c[o1] = int(gl_GlobalInvocationID.x);
    c[o2] = int(gl_GlobalInvocationID.y);
    if (c[o1] >= n[o1] || c[o2] >= n[o2]) {
        return;
    }
    vec4 here = imageLoad(light_img, c);
    float t = 1.0;
    if (pc.info.w == 0) {
        vec3 q = vec3(c) + pc.delta.xyz;
        t = previous_t(q, axis, o1, o2) * exp(-extinction(value_at_cell(vec3(c))) * pc.delta.w);
    }
    imageStore(light_img, c, vec4(t, here.y, 0.0, 0.0));
}
