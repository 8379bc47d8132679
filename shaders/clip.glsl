// Rule 10's clipping plane (src/scene/clip.rs, RenderSettings): cuts the ray's segment a -> b (texture space) to the
// half-space dot(frame.clip_plane.xyz, p) + frame.clip_plane.w >= 0, exactly, before any sample is placed, so the
// march's sample grid starts where the plane starts the ray (as it starts at a slab face). Both ray setups reach it
// through march(). Without a plane the uniform is (0, 0, 0, 1) and every segment is kept unchanged.
// Returns false where nothing (or a single point) is left; `cut` says whether the plane moved the start.
bool clip_segment(inout vec3 a, inout vec3 b, out bool cut) {
    float fa = dot(frame.clip_plane.xyz, a) + frame.clip_plane.w;
    float fb = dot(frame.clip_plane.xyz, b) + frame.clip_plane.w;
    cut = fa < 0.0;
    if ((fa < 0.0 && fb <= 0.0) || (fb < 0.0 && fa <= 0.0)) {
        return false;
    }
    // The signs differ here (or both ends are kept), so fa - fb is not zero where it is divided by.
    if (fa < 0.0) {
        a = mix(a, b, fa / (fa - fb));
    } else if (fb < 0.0) {
        b = mix(a, b, fa / (fa - fb));
    }
    return true;
}
