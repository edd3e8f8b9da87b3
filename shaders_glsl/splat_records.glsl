// Element offsets in the splat renderer's flat per-splat buffers, declared
// once as SPLAT_GEOM, SPLAT_REC_A and SPLAT_REC_B in splatedit/render/uniforms.py
// (tests/render/test_uniforms.py checks these constants against them).

// geometry (float geom[]): GEOM_STRIDE floats per splat, centre, u, v
const uint GEOM_STRIDE = 9u;
const uint GEOM_CENTER = 0u;
const uint GEOM_U = 3u;
const uint GEOM_V = 6u;

// pre-pass records A (vec4 recA[]): RECA_STRIDE vec4 per slot
const uint RECA_STRIDE = 3u;
const uint RECA_MS_CN = 0u;
const uint RECA_MT_TC = 1u;
const uint RECA_MW_R = 2u;

// pre-pass records B (uvec4 recB[]): RECB_STRIDE uvec4 per slot
const uint RECB_STRIDE = 2u;
const uint RECB_CENTER = 0u;
const uint RECB_PACKED = 1u;
