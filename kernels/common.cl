// The prelude of every ngi program: kernels/common.cl comes first, then the program's files in the order its entry
// in host/src/runtime/programs.cpp lists them. OpenCL C 1.2, no extensions: the same source builds on PoCL (CPU)
// and GPU drivers. Helpers that only some programs need live in their own file (luminance.cl, sh_basis.cl,
// rng.cl, geometry.cl), listed by the programs that use them.

#define NGI_CAT_(a, b) a##b
#define NGI_CAT(a, b) NGI_CAT_(a, b)
