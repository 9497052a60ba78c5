// Probes of driver behaviour that the OpenCL API does not report (host/src/runtime/context.cpp).

// Counts the iterations of one loop of n steps. Every step reads memory (ones[] holds 1s), so the compiler cannot
// replace the loop by its closed form. A driver with a loop limiter (Mesa llvmpipe ends every loop after 65,535
// iterations in total) reports fewer than n.
__kernel void count_loop_iterations(const int n, __global const int* ones, __global int* count) {
    if (get_global_id(0) != 0) return;
    int c = 0;
    for (int i = 0; i < n; ++i) c += ones[i & 7];
    count[0] = c;
}
