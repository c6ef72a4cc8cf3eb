// lavapipe ends a SIMD group's loops silently after 65,535 iterations in
// all, so the per-path loop (path_loop.comp), which runs many bounces in one
// invocation, counts them: every loop that a bounce can reach calls
// COUNT_LOOP_ITERATION() first thing in its body (tests/suite/loop_count.rs
// checks). Other kernels compile it to nothing.
#ifndef LOOP_COUNT_GLSL
#define LOOP_COUNT_GLSL

#ifdef COUNT_LOOP_ITERATIONS
uint loop_iterations = 0u;
#define COUNT_LOOP_ITERATION() loop_iterations++
#else
#define COUNT_LOOP_ITERATION()
#endif

#endif
