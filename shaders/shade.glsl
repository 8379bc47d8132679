// Blinn-Phong (rule 5), two-sided, at texture position p: `view` is the unit direction towards the eye, in world
// space; the light is frame.light_dir, or a headlight along `view`. With the light grid (rule 9) the light is
// shadowed by T and the ambient term occluded by O. `fade` (volume shading: gradient_fade) mixes from the flat
// colour rgb·(ambient + diffuse·light), a face turned to the light, to the lit one; surfaces pass 1.
vec3 shade(vec3 rgb, vec3 g, vec3 view, vec3 p, float fade) {
    vec4 s = frame.shading;
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
    vec3 flat_rgb = rgb * (ambient + s.y * c);
    vec3 gw = mat3(frame.gradient_to_world) * g;
    float len = length(gw);
    if (len < 1e-8) {
        return fade < 1.0 ? flat_rgb : rgb;
    }
    vec3 n = gw / len;
    n = dot(n, view) < 0.0 ? -n : n;
    vec3 l = frame.light_dir.w > 0.5 ? frame.light_dir.xyz : view;
    float ndl = max(dot(n, l), 0.0);
    vec3 half_sum = l + view;
    float hl = length(half_sum);
    float ndh = hl > 1e-6 ? max(dot(n, half_sum / hl), 0.0) : 0.0;
    float spec = ndl > 0.0 ? pow(ndh, s.w) : 0.0;
    return mix(flat_rgb, rgb * (ambient + s.y * ndl * c) + s.z * spec * c, fade);
}

// Rule 5's fade of volume shading with the gradient g (value per voxel), with `shading_fade`: smoothstep from 0 to
// frame.voxel_world.x (`shading_fade` x the window's width; 0: no fade). Where the data is flat its gradient is
// noise, whose direction turns with every shift of the sample lattice; a highlight would follow it.
float gradient_fade(vec3 g) {
    float width = frame.voxel_world.x;
    if (width <= 0.0) {
        return 1.0;
    }
    float x = clamp(length(g) / width, 0.0, 1.0);
    return x * x * (3.0 - 2.0 * x);
}
