// Host transfers done as kernels, used only on the Oclgrind simulator (host/src/runtime/context.cpp).
//
// Oclgrind 21.10's --uninitialized plugin mishandles host writes that do not cover a whole buffer: each
// clEnqueueWriteBuffer / clEnqueueFillBuffer store re-creates the buffer's shadow memory with the size of that
// one store (ShadowMemory::allocate via hostMemoryStore), so every earlier upload into the same buffer is
// forgotten and an upload at a nonzero offset lands past the new shadow. Kernels would then report
// "uninitialized" reads of data the host did write. Stores made by a kernel update the shadow precisely, so on
// Oclgrind a partial upload goes to a whole staging buffer and copy_words moves it into place, and fill_zero
// clears with zero_words: exactly the bytes the host wrote become initialized, nothing more. Device-to-device copies
// (clEnqueueCopyBuffer) lose the shadow the same way when source or destination is a sub-buffer (the op harness's
// guarded buffers): on Oclgrind they go through copy_words as well.

__kernel void copy_words(__global const uint* restrict src, const ulong src_off, __global uint* restrict dst,
                         const ulong dst_off, const ulong n) {
    const size_t i = get_global_id(0);
    if (i < n) dst[dst_off + i] = src[src_off + i];
}

__kernel void zero_words(__global uint* restrict dst, const ulong dst_off, const ulong n) {
    const size_t i = get_global_id(0);
    if (i < n) dst[dst_off + i] = 0u;
}
