#pragma once
/// @file kernel_clones.hpp
/// @brief Hot loops compiled twice: for x86-64-v3 (AVX2, FMA: three-operand forms and fused
/// multiply-adds) and for any x86-64, the variant picked once at load time (GCC's
/// target_clones), so the default build runs everywhere and uses the wider units where they
/// exist. Used by the rod's kernels (the stencil, the frame transport, the banded
/// factorization and solves) and the wall's sparse forward solves. Results of the two variants
/// differ by round-off only; FLOWIRE_NO_KERNEL_CLONES builds the default variant alone.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && defined(__linux__) && \
    !defined(FLOWIRE_NO_KERNEL_CLONES)
#define FLOWIRE_KERNEL_CLONES __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define FLOWIRE_KERNEL_CLONES
#endif
