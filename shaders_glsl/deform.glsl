// Per-frame deformation parameters (std140 uniform block, set 0, binding
// DEFORM_BINDING, defined by the including file).  dC of a basis with up to
// RENDER_MAX_BASIS_COLUMNS = 16 columns, zero-padded to whole groups of 4:
// dC[3g + i] = (dC_{4g}, .., dC_{4g+3})[i], i = x, y, z.  Only this 192-byte
// block is uploaded when the displacement changes.  rot: per group g the
// rotation of handle g (rotation-aware mode, rotation.glsl): rot[4g] = (unit
// axis, angle; 0 = none), rot[4g + 1 + i] = (D_0, .., D_3)[i] (frame offsets).
// Declared once as DEFORM_UBO in splatedit/render/uniforms.py (checked by
// tests/render/test_uniforms.py).

const int MAX_BASIS_GROUPS = 4;

// Basis rows (storage vec4 basis[], or the vertex path's in_basis attributes):
// BASIS_STRIDE vec4 per group of 4 columns, B, Bx, By, Bz at BASIS_<FIELD>
// (BASIS_GROUP in splatedit/render/uniforms.py).
const uint BASIS_STRIDE = 4u;
const uint BASIS_B = 0u;
const uint BASIS_BX = 1u;
const uint BASIS_BY = 2u;
const uint BASIS_BZ = 3u;

layout(std140, set = 0, binding = DEFORM_BINDING) uniform Deform {
    vec4 dC[3 * MAX_BASIS_GROUPS];
    vec4 rot[4 * MAX_BASIS_GROUPS];
} D;
