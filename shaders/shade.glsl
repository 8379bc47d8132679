// Blinn-Phong (rule 5), two-sided, at texture position p: `view` is the unit direction towards the eye, in world
// space; the light is frame.light_dir, or a headlight along `view`. With the light grid (rule 9) the light is
// shadowed by T and the ambient term occluded by O.
vec3 shade(vec3 rgb, vec3 g, vec3 view, vec3 p) {
    vec3 gw = mat3(frame.gradient_to_world) * g;
    float len = length(gw);
    if (len < 1e-8) {
        return rgb;
    }
    vec3 n = gw / len;
    n = dot(n, view) < 0.0 ? -n : n;
    vec3 l = frame.light_dir.w > 0.5 ? frame.light_dir.xyz : view;
    float ndl = max(dot(n, l), 0.0);
    vec3 half_sum = l + view;
    float hl = length(half_sum);
    float ndh = hl > 1e-6 ? max(dot(n, half_sum / hl), 0.0) : 0.0;
    vec4 s = frame.shading;
    float spec = ndl > 0.0 ? pow(ndh, s.w) : 0.0;
    vec3 c = frame.light_color.rgb;
    float ambient = s.x;
#if defined(LIGHT_VOLUME)
    uint grid = uint(frame.light_grid.w);
    if ((grid & 1u) != 0u) {
        c *= textureLod(sampler3D(light_tex, linear_smp), p + frame.light_grid.xyz, 0.0).x;
    }
    if ((grid & 2u) != 0u) {
        ambient *= textureLod(sampler3D(light_tex, linear_smp), p, 0.0).y;
    }
#endif
    return rgb * (ambient + s.y * ndl * c) + s.z * spec * c;
}
