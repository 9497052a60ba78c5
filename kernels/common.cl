// Shared by every ngi program: prepended to each kernels/*.cl file before it is built.
// OpenCL C 1.2, no extensions: the same source builds on PoCL (CPU) and GPU drivers.

#define NGI_CAT_(a, b) a##b
#define NGI_CAT(a, b) NGI_CAT_(a, b)

// Rec. 709 luminance. The weights are the host's (build options LUMA_R, LUMA_G, LUMA_B: luminance_defines(),
// host/src/ops/luminance.hpp), so the helper exists only in the programs built with them; a kernel file that calls
// it checks for them with #error.
#ifdef LUMA_R
static inline float ngi_luminance(float3 c) { return LUMA_R * c.x + LUMA_G * c.y + LUMA_B * c.z; }
#endif

// ---- real spherical harmonics, bands 0-2 (docs/CONVENTIONS.md section 14) -------------------------------
// Shared by sh.cl (evaluation) and pathtrace.cl (projection of path-traced radiance) so both use one basis.

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
