// The analytic ray setup, shared by the fragment (march_analytic.frag) and compute (march_compute.comp) marches:
// intersect pixel `frag`'s ray with the slab box (slab method) in texture space and march the segment.
vec4 analytic_pixel(vec2 frag) {
    vec3 origin = ray_origin(frag);
    // t is distance along the view axis, so the near plane is t = near: clamping t0 to it starts rays where
    // rasterisation would clip them.
    vec3 dir = ray_direction(frag);
    vec3 inv = 1.0 / dir;
    vec3 t_lo = (frame.slab_lo.xyz - origin) * inv;
    vec3 t_hi = (frame.slab_hi.xyz - origin) * inv;
    vec3 t_min = min(t_lo, t_hi);
    vec3 t_max = max(t_lo, t_hi);
    float t0 = max(max(max(t_min.x, t_min.y), t_min.z), frame.ray_forward.w);
    float t1 = min(min(t_max.x, t_max.y), t_max.z);
    if (!(t1 > t0)) {
        return output_pixel(background_pixel(), 0u);
    }
    return march(origin + dir * t0, origin + dir * t1, frag);
}
