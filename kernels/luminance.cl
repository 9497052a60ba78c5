// Rec. 709 luminance, listed by the programs that weigh colours by it (pathtrace, voxel_field, voxel_ltf in
// host/src/runtime/programs.cpp). The weights are the host's: build options LUMA_R, LUMA_G, LUMA_B
// (luminance_defines(), host/src/ops/luminance.hpp).
#if !defined(LUMA_R) || !defined(LUMA_G) || !defined(LUMA_B)
#error "luminance.cl needs the weights LUMA_R, LUMA_G, LUMA_B: build the program with luminance_defines() (host/src/ops/luminance.hpp)"
#endif

static inline float ngi_luminance(float3 c) { return LUMA_R * c.x + LUMA_G * c.y + LUMA_B * c.z; }
