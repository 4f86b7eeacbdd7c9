// One triangle that covers the whole viewport, generated from the vertex
// index: no vertex buffer, and no diagonal seam. Two triangles sharing a
// diagonal would shade the quads straddling it twice (helper lanes); the
// TWO_TRIANGLES def draws that way on purpose, for comparison.
#define_import_path loupe::fullscreen

struct FullscreenOut {
    @builtin(position) position: vec4<f32>,
    // 0..1 across the viewport, y down (texture convention).
    @location(0) uv: vec2<f32>,
}

#ifdef TWO_TRIANGLES
// Vertex count: 6. Corners of the quad as two triangles.
fn fullscreen(vertex_index: u32) -> FullscreenOut {
    var corners = array<vec2<f32>, 6>(
        vec2(-1.0, -1.0), vec2(1.0, -1.0), vec2(-1.0, 1.0),
        vec2(-1.0, 1.0), vec2(1.0, -1.0), vec2(1.0, 1.0),
    );
    let p = corners[vertex_index % 6u];
    return FullscreenOut(vec4(p, 0.0, 1.0), vec2(p.x * 0.5 + 0.5, 0.5 - p.y * 0.5));
}
#else
// Vertex count: 3. (-1,-1), (3,-1), (-1,3): the viewport is the part of the
// triangle inside clip space, everything else is clipped for free.
fn fullscreen(vertex_index: u32) -> FullscreenOut {
    let p = vec2(f32((vertex_index << 1u) & 2u), f32(vertex_index & 2u)) * 2.0 - 1.0;
    return FullscreenOut(vec4(p, 0.0, 1.0), vec2(p.x * 0.5 + 0.5, 0.5 - p.y * 0.5));
}
#endif
