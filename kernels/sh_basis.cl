// Real spherical harmonics, bands 0-2 (docs/CONVENTIONS.md section 14): the one basis of every program that
// evaluates SH (sh, probe_shade) or projects onto it (voxel_field: path-traced radiance), so all use the same.
// No build options.

// Y_k(d) for k = l (l + 1) + m of a unit direction d = (x, y, z) in the frame the coefficients were projected in.
// The constants are sqrt((2l + 1) / (4 pi) (l - |m|)! / (l + |m|)!) times the Legendre factors; odd m carry the
// Condon-Shortley sign (-1)^m.
static inline void sh9(float x, float y, float z, float* Y) {
    Y[0] = 0.28209479177387814f;
    Y[1] = -0.48860251190291992f * y;
    Y[2] = 0.48860251190291992f * z;
    Y[3] = -0.48860251190291992f * x;
    Y[4] = 1.0925484305920792f * x * y;
    Y[5] = -1.0925484305920792f * y * z;
    Y[6] = 0.31539156525252005f * (3.0f * z * z - 1.0f);
    Y[7] = -1.0925484305920792f * x * z;
    Y[8] = 0.54627421529603959f * (x * x - y * y);
}

// Cosine-lobe convolution factors A_l (Ramamoorthi and Hanrahan 2001): pi, 2 pi / 3, pi / 4.
__constant float kLobe[9] = {3.14159265358979f, 2.09439510239320f, 2.09439510239320f, 2.09439510239320f,
                             0.78539816339745f, 0.78539816339745f, 0.78539816339745f, 0.78539816339745f,
                             0.78539816339745f};
