// Gaussian splatting, compute tile rasterizer (splatedit/render/gaussian/tiles.py):
// set 1 of its passes.  After the depth sort (order[0, n visible) front to
// back), every visible Gaussian emits one (tile id, Gaussian) pair per
// TILE x TILE tile its ellipse of alpha >= floor touches, in depth order (a
// device-wide exclusive scan of the per-Gaussian tile counts gives each its
// slots); a stable radix sort by tile id keeps depth order inside a tile; the
// ranges pass finds each tile's run of pairs; one workgroup per tile blends
// its Gaussians front to back (gs_tile_blend.glsl).  The layout is TILE_SET in
// gaussian/tiles.py, the push constants TILE_PUSH in splatedit/render/uniforms.py.

const uint TILE = 16u;
const uint TBLOCK = 2048u;           // visible Gaussians per scan workgroup (256 x 8)
const uint TITEMS = 8u;

layout(std430, set = 1, binding = 0) buffer TPairKeys { uint pair_keys[]; };   // tile id
layout(std430, set = 1, binding = 1) buffer TPairVals { uint pair_vals[]; };   // Gaussian index
// [0]: pairs wanted, [1]: -, [2]: pairs kept (min(wanted, capacity): the tile sort's count),
// [3]: -, [4..8): dispatch of one workgroup per TBLOCK visible Gaussians (x, y, z, n visible),
// [8 + b]: tile count of block b, scanned to its first slot
layout(std430, set = 1, binding = 2) buffer TScan { uint tscan[]; };
layout(std430, set = 1, binding = 3) buffer TRanges { uvec2 ranges[]; };       // [first, end) per tile
// the tile sort's dispatch arguments (gpu_sort.py RadixSort.args): w = pairs sorted
layout(std430, set = 1, binding = 4) readonly buffer TSortArgs { uint targs[4]; };

layout(push_constant) uniform TilePush {
    uint capacity;       // pairs the pair buffers hold
    uint tiles_x;        // tiles per row
    uint tiles_y;        // tile rows
    float t_min;         // blending stops before the transmittance would drop below this
} TP;

// the tiles [lo, hi] (inclusive, x and y) of Gaussian g's ellipse; false when none
bool tile_rect(uint g, out uvec2 lo, out uvec2 hi) {
    vec4 c = rec[REC_STRIDE * g + REC_CENTER];
    vec4 ax = rec[REC_STRIDE * g + REC_AXES];
    vec2 ext = abs(ax.xy) + abs(ax.zw);
    // pixels whose centre (x + 0.5) lies within the box
    vec2 a = max(c.xy - ext - 0.5, vec2(0.0));
    vec2 b = min(c.xy + ext - 0.5, F.viewport.xy - 1.0);
    if (any(lessThan(b, a))) return false;
    lo = uvec2(a) / TILE;
    hi = min(uvec2(b) / TILE, uvec2(TP.tiles_x - 1u, TP.tiles_y - 1u));
    return true;
}

uint tile_count(uint g) {
    uvec2 lo, hi;
    if (!tile_rect(g, lo, hi)) return 0u;
    uvec2 s = hi - lo + 1u;
    return s.x * s.y;
}
