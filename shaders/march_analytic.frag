#version 450
// The analytic ray setup: intersect the pixel's ray with the slab box (slab method) in texture space.
#include "frame.glsl"
#include "march.glsl"

layout(location = 0) out vec4 out_color;

void main() {
    vec3 origin = frame.eye_tex.xyz;
    // Parameterised so that t = 1 is the near plane: clamping t0 to 1 starts rays there, as rasterisation does.
    vec3 dir = near_point(gl_FragCoord.xy) - origin;
    vec3 inv = 1.0 / dir;
    vec3 t_lo = (frame.slab_lo.xyz - origin) * inv;
    vec3 t_hi = (frame.slab_hi.xyz - origin) * inv;
    vec3 t_min = min(t_lo, t_hi);
    vec3 t_max = max(t_lo, t_hi);
    float t0 = max(max(max(t_min.x, t_min.y), t_min.z), 1.0);
    float t1 = min(min(t_max.x, t_max.y), t_max.z);
    if (!(t1 > t0)) {
        out_color = vec4(frame.background.rgb, 1.0);
        return;
    }
    out_color = march(origin + dir * t0, origin + dir * t1);
}
