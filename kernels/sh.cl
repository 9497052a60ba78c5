// Real spherical harmonics, bands 0-2 (9 coefficients), with the Condon-Shortley phase (seeds 004 and 002).
// Conventions (basis order, axes, coefficient layout, the cosine lobe): docs/CONVENTIONS.md section 14.
// The basis sh9() and the lobe factors kLobe are sh_basis.cl's, listed before this file: the voxel field projects
// path-traced radiance onto the same basis.

// out[i][c] = sum_k coef[i][c][k] * w_k * Y_k(dir_i) for n items, C channels: radiance along dir (irradiance = 0)
// or irradiance around the normal dir (irradiance = 1: w_k = A_l). Directions need not be unit length (they are
// normalized; a zero direction gives band 0 only). Layouts: coef [n][C][9], dir [n][3], out [n][C].
__kernel void sh_evaluate(__global const float* restrict coef, __global const float* restrict dir, const int n,
                          const int channels, const int irradiance, __global float* restrict out) {
    const int i = get_global_id(0);
    if (i >= n) return;
    float x = dir[3 * i], y = dir[3 * i + 1], z = dir[3 * i + 2];
    const float len = sqrt(x * x + y * y + z * z);
    const float inv = len > 0.0f ? 1.0f / len : 0.0f;
    x *= inv;
    y *= inv;
    z *= inv;
    float Y[9];
    sh9(x, y, z, Y);
    if (len == 0.0f)
        for (int k = 1; k < 9; ++k) Y[k] = 0.0f;
    for (int c = 0; c < channels; ++c) {
        __global const float* a = coef + ((size_t)i * channels + c) * 9;
        float s = 0.0f;
        for (int k = 0; k < 9; ++k) s = mad(a[k] * (irradiance ? kLobe[k] : 1.0f), Y[k], s);
        out[(size_t)i * channels + c] = s;
    }
}
