#pragma once
// The rod's hot loops (the stencil kernel, ~1,000 scalar multiply-adds; the frame transport;
// the banded factorization and solves) are also compiled for x86-64-v3 (AVX2, FMA:
// three-operand forms and fused multiply-adds) on x86-64 with GCC, and the variant is picked
// once at load time, so the default build still runs on any x86-64. Results differ between
// the two variants by round-off only (FLOWIRE_ROD_NO_KERNEL_CLONES builds the default
// variant alone).
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && defined(__linux__) && \
    !defined(FLOWIRE_ROD_NO_KERNEL_CLONES)
#define FLOWIRE_ROD_KERNEL_CLONES __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define FLOWIRE_ROD_KERNEL_CLONES
#endif
