// A program for sanitizer builds only, run by check_sanitizer_probe.cmake:
//   sanitizer_probe none    starts and finishes MPI and PETSc, leaks nothing: must pass
//   sanitizer_probe new     leaks a new[] array from flowire::test::leak_new
//   sanitizer_probe petsc   leaks a PETSc vector created in flowire::test::leak_petsc
//                           (whose allocation stack runs through libpetsc)
//   sanitizer_probe ubsan   overflows a signed integer in flowire::test::overflow
// Every case but "none" must fail under the test environment of a sanitizer build.
#include <climits>
#include <cstdio>
#include <cstring>

#ifdef FLOWIRE_PROBE_PETSC
#include <petscvec.h>
#endif

namespace flowire::test {

// Stored in a volatile global that is cleared right away: the optimizer cannot drop the
// allocation and LeakSanitizer sees no pointer left to it.
double* volatile g_sink = nullptr;

[[gnu::noinline]] void leak_new() {
  g_sink = new double[1000];
  g_sink[0] = 1.0;
  g_sink = nullptr;
}

[[gnu::noinline]] int overflow(int a) { return a + 1; }

#ifdef FLOWIRE_PROBE_PETSC
[[gnu::noinline]] int leak_petsc() {
  Vec v = nullptr;
  if (VecCreateSeq(PETSC_COMM_SELF, 100, &v) != 0) return 1;
  if (VecSet(v, 1.0) != 0) return 1;
  return 0;  // no VecDestroy
}
#endif

}  // namespace flowire::test

int main(int argc, char** argv) {
  const char* mode = argc > 1 ? argv[1] : "none";
#ifdef FLOWIRE_PROBE_PETSC
  if (PetscInitialize(&argc, &argv, nullptr, nullptr) != 0) return 1;
#endif
  int rc = 0;
  if (std::strcmp(mode, "new") == 0) {
    flowire::test::leak_new();
  } else if (std::strcmp(mode, "ubsan") == 0) {
    volatile int big = INT_MAX;
    std::printf("%d\n", flowire::test::overflow(big));
  } else if (std::strcmp(mode, "petsc") == 0) {
#ifdef FLOWIRE_PROBE_PETSC
    rc = flowire::test::leak_petsc();
#else
    std::fprintf(stderr, "sanitizer_probe: built without PETSc\n");
    rc = 2;
#endif
  } else if (std::strcmp(mode, "none") != 0) {
    std::fprintf(stderr, "sanitizer_probe: unknown case %s\n", mode);
    rc = 2;
  }
#ifdef FLOWIRE_PROBE_PETSC
  if (PetscFinalize() != 0) return 1;
#endif
  return rc;
}
