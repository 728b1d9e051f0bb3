#pragma once
// SMC_MULTIVERSION (internal): the time-domain stepping loops are compiled
// twice, for the x86-64 baseline and for x86-64-v3 (AVX2 and fused
// multiply-add, which shorten the force and mode updates by a fifth), and the
// dynamic loader picks one for the CPU at start-up (GCC function
// multi-versioning: an ifunc, resolved once, no per-call cost). Elsewhere
// (other compilers or architectures, or SMC_MACHINING_NO_MULTIVERSION) it
// is nothing and the baseline code runs.
//
// Results are bit-identical run after run on one machine; between a CPU with
// fused multiply-add and one without, they differ by rounding.

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && \
    !defined(SMC_MACHINING_NO_MULTIVERSION)
#define SMC_MULTIVERSION __attribute__((target_clones("default", "arch=x86-64-v3")))
#else
#define SMC_MULTIVERSION
#endif
