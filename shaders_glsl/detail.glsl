// Detail-preserving deformation (splatedit/deform/detail.py): the basis rows
// of a splat are evaluated at its BASE point b = p - lambda n_b, so dp = d(b)
// and Jm = J(b) - I; the detail is re-attached with M = J P + n' n_b^T:
//   n' = normalize(J^-T n_b) (cofactor form: no division by det J)
//   p' = b + d(b) + lambda n',   u' = J (u - (u.n_b) n_b) + (u.n_b) n',  v' likewise.
// The including file defines DETAIL_BINDING.

layout(std430, set = 0, binding = DETAIL_BINDING) readonly buffer Detail { vec4 detail[]; };  // (n_b, lambda) per splat

void detail_attach(vec4 nl, vec3 dp, mat3 Jm, inout vec3 p, inout vec3 u, inout vec3 v) {
    vec3 nb = nl.xyz;
    mat3 J = mat3(1.0) + Jm;
    vec3 n = nb.x * cross(J[1], J[2]) + nb.y * cross(J[2], J[0]) + nb.z * cross(J[0], J[1]);
    n *= inversesqrt(max(dot(n, n), 1e-30));
    float hu = dot(u, nb), hv = dot(v, nb);
    p += dp + nl.w * (n - nb);
    u = J * (u - hu * nb) + hu * n;
    v = J * (v - hv * nb) + hv * n;
}
