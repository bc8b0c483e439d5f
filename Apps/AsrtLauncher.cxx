// The `asrt` program's entry point: sets OpenMP's wait policy, then loads the program itself
// (asrtProgram, asrt.cxx and the Cli*.cxx commands) and runs it.
//
// OpenMP threads that wait passively between parallel regions: libgomp's default is to spin for
// a while before sleeping, which burns CPU on every core while the main thread works alone (a
// movie's store reads, interpolation and file writing between traced passes), a share of a
// movie's CPU for no gain in wall time (bench/REPORT.md, the movies). libgomp reads
// OMP_WAIT_POLICY once, as it loads. This launcher links none of the program's libraries: it sets
// the policy, then loads them, so they start once (running the program itself again with the
// policy set started all of its libraries twice). A user's own OMP_WAIT_POLICY or GOMP_SPINCOUNT
// is left alone.
#include <dlfcn.h>

#include <cstdio>
#include <cstdlib>

namespace
{
/// The exit code when the program's library cannot be loaded (sysexits.h's EX_SOFTWARE).
constexpr int kCannotLoad = 70;
}

int main(int argc, char* argv[])
{
  if (!std::getenv("OMP_WAIT_POLICY") && !std::getenv("GOMP_SPINCOUNT"))
    setenv("OMP_WAIT_POLICY", "passive", 1);
  // Found through this launcher's RUNPATH: the build tree's library folder, or the installed one.
  void* program = dlopen(ASRT_PROGRAM_LIBRARY, RTLD_NOW | RTLD_GLOBAL);
  if (!program)
  {
    std::fprintf(stderr, "asrt: cannot load the program's library: %s\n", dlerror());
    return kCannotLoad;
  }
  using ProgramMain = int (*)(int, char**);
  const auto run = reinterpret_cast<ProgramMain>(dlsym(program, "asrtProgramMain"));
  if (!run)
  {
    std::fprintf(stderr, "asrt: %s has no asrtProgramMain: %s\n", ASRT_PROGRAM_LIBRARY, dlerror());
    return kCannotLoad;
  }
  return run(argc, argv);
}
