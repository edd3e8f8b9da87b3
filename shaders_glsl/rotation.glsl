// Rotation-aware handles (splatedit/deform/rotation.py, issue 9): the arc term
// F(s) v of one handle and its Jacobian, from the handle's 4 basis columns.
//   s = sum_k B_k (weight field: 1 on the handle, 0 on the fixed band)
//   v = sum_k B_k D_k, D_k = control frame minus rotation centre (GPU units)
//   F(s) = (R(s) - I) / s = a1 K + a2 K^2, K = [axis]x, R(s) = exp(s angle K)
//   dp += F(s) v;  (J - I) += F(s) grad v + (F'(s) v) grad s^T
// axis_angle = (unit axis, angle); Dx/Dy/Dz = x/y/z of D_0..D_3.
// Self-contained (no bindings), so other deformation shaders can call it.

// c1 (k x y) + c2 (k x (k x y))
vec3 rot_arc_apply(vec3 k, float c1, float c2, vec3 y) {
    vec3 ky = cross(k, y);
    return c1 * ky + c2 * cross(k, ky);
}

// (a1, a2, b1, b2): F(s) = a1 K + a2 K^2, F'(s) = b1 K + b2 K^2.  Series below
// |x| = 0.1 (float32: the closed forms of b1, b2 cancel there; the series'
// first dropped terms are below 2e-10)
vec4 rot_arc_coefficients(float angle, float s) {
    float x = s * angle;
    float x2 = x * x;
    float f1, f2, g1, g2;
    if (abs(x) < 0.1) {
        f1 = 1.0 - x2 / 6.0 + x2 * x2 / 120.0;
        f2 = x * (0.5 - x2 / 24.0 + x2 * x2 / 720.0);
        g1 = x * (-1.0 / 3.0 + x2 / 30.0 - x2 * x2 / 840.0);
        g2 = 0.5 - x2 / 8.0 + x2 * x2 / 144.0;
    } else {
        float sn = sin(x), cs = cos(x), h = sin(0.5 * x);
        float omc = 2.0 * h * h;                    // 1 - cos x without cancellation
        f1 = sn / x;
        f2 = omc / x;
        g1 = (x * cs - sn) / x2;
        g2 = (x * sn - omc) / x2;
    }
    return vec4(angle * f1, angle * f2, angle * angle * g1, angle * angle * g2);
}

void rotation_blend(vec4 axis_angle, vec4 Dx, vec4 Dy, vec4 Dz,
                    vec4 B, vec4 Bx, vec4 By, vec4 Bz, inout vec3 dp, inout mat3 Jm) {
    vec3 k = axis_angle.xyz;
    float s = dot(B, vec4(1.0));
    vec3 v = vec3(dot(B, Dx), dot(B, Dy), dot(B, Dz));
    vec3 gs = vec3(dot(Bx, vec4(1.0)), dot(By, vec4(1.0)), dot(Bz, vec4(1.0)));
    vec4 a = rot_arc_coefficients(axis_angle.w, s);
    dp += rot_arc_apply(k, a.x, a.y, v);
    vec3 fv = rot_arc_apply(k, a.z, a.w, v);
    // column j of grad v = d v / d x_j
    Jm[0] += rot_arc_apply(k, a.x, a.y, vec3(dot(Bx, Dx), dot(Bx, Dy), dot(Bx, Dz))) + fv * gs.x;
    Jm[1] += rot_arc_apply(k, a.x, a.y, vec3(dot(By, Dx), dot(By, Dy), dot(By, Dz))) + fv * gs.y;
    Jm[2] += rot_arc_apply(k, a.x, a.y, vec3(dot(Bz, Dx), dot(Bz, Dy), dot(Bz, Dz))) + fv * gs.z;
}
