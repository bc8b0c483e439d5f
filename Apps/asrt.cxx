// asrt: the command-line face of ASRT. One program, one subcommand per job; each chains the VTK
// filters (vtkGeodesicSource, the PostgreSQL writer and reader, vtkGeodesicSceneGeometry) and
// VTK's writers. `asrt --help` lists the subcommands, `asrt COMMAND --help` explains one.
#include "Cli.h"

#include "AsrtTypes.h"
#include "AtomicFile.h"
#include "Progress.h"
#include "RayStore.h"
#include "VtkMessages.h"

#include "vtkObject.h"

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

namespace
{
using namespace asrt::cli;

struct Command
{
  const char* name;
  const char* summary;
  int (*run)(const std::vector<std::string>&);
};

// A new subcommand is a row here and a run function (see Cli.h).
const Command kCommands[] = {
  { "trace", "trace a scene to PNG, VTI and VTP files (and store it in PostgreSQL)", runTrace },
  { "list", "list the frames stored in PostgreSQL", runList },
  { "show", "show a stored frame's parameters; export it to PNG, VTI, VTP", runShow },
  { "interpolate", "the movie frames between two stored frames: PNG, VTI, .pvd, a movie",
    runInterpolate },
  { "movie", "a movie along a path at a quality target: key frames planned, stored and reused",
    runMovie },
  { "bundle", "render a 3D view of rays around the hole (PNG, or a window)", runBundle },
  { "bench", "measure time and accuracy of the integrator presets on a small frame", runBench },
  { "db", "start, inspect, stop or delete the private PostgreSQL server; init a schema", runDb },
};

void usage(std::FILE* out)
{
  std::fprintf(out, "Usage: asrt COMMAND [options]   (asrt COMMAND --help for one command)\n\n"
                    "Black-hole ray tracing with accumulation in PostgreSQL (ASRT).\n\n"
                    "Commands:\n");
  for (const Command& c : kCommands)
    std::fprintf(out, "  %-12s %s\n", c.name, c.summary);
  std::fprintf(out,
               "\nExamples:\n"
               "  asrt trace Data/scenes/fig1-cylinders.json -o out/\n"
               "  asrt trace Data/scenes/fig1-cylinders.json --sweep mass=0.1:1.2:5 -o out/ramp\n"
               "  asrt trace Data/scenes/fig4-mass-start.json --store=ramp\n"
               "  asrt list\n"
               "  asrt show 1 --png frame1.png\n"
               "  asrt interpolate 1 2 -n 28 -o movie/\n"
               "  asrt bundle Data/scenes/fig1-cylinders.json -o bundle.png\n"
               "  mpirun -np 4 asrt trace Data/scenes/kerr-disk.json --mpi --store\n\n%s",
               kExitCodeHelp);
}

int report(const char* command, const char* kind, const std::string& message, int code)
{
  if (!silentParallelFailure())
  {
    const ParallelRun* run = parallelRun();
    if (run && run->rank != 0)
      std::fprintf(stderr, "asrt %s (process %d): %s%s\n", command, run->rank, kind,
                   message.c_str());
    else
      std::fprintf(stderr, "asrt %s: %s%s\n", command, kind, message.c_str());
  }
  return finishParallelRun(code);
}
}

/// The program, run by the `asrt` launcher (AsrtLauncher.cxx) once it has set OpenMP's wait
/// policy and loaded this library.
extern "C" __attribute__((visibility("default"))) int asrtProgramMain(int argc, char* argv[])
{
  if (argc < 2)
  {
    usage(stderr);
    return kUsage;
  }
  const std::string name = argv[1];
  if (name == "--help" || name == "-h" || name == "help")
  {
    usage(stdout);
    return kOk;
  }
  if (name == "--version")
  {
    std::printf("asrt %s\n", ASRT_VERSION);
    return kOk;
  }
  const Command* command = nullptr;
  for (const Command& c : kCommands)
    if (name == c.name)
      command = &c;
  if (!command)
  {
    std::fprintf(stderr, "asrt: unknown command '%s' (try asrt --help)\n", name.c_str());
    return kUsage;
  }
  // Errors reach the user as one line each, through the exceptions below; anything VTK would
  // print on its own is caught by observers where it arises, or routed as a stray (VtkMessages.h).
  asrt::tools::installInterruptHandler();
  asrt::tools::routeVtkMessages();
  const std::vector<std::string> args(argv + 2, argv + argc);
  try
  {
    return finishParallelRun(command->run(args));
  }
  catch (const UsageError& e)
  {
    std::fprintf(stderr, "asrt %s: %s\nTry 'asrt %s --help'.\n", command->name, e.what(),
                 command->name);
    return finishParallelRun(kUsage);
  }
  catch (const InputError& e)
  {
    return report(command->name, "", e.what(), kBadInput);
  }
  catch (const asrt::InvalidParameter& e)
  {
    return report(command->name, "", e.what(), kBadInput);
  }
  catch (const DatabaseError& e)
  {
    return report(command->name, "database: ", e.what(), kDatabase);
  }
  catch (const asrt::StoreError& e)
  {
    return report(command->name, "database: ", e.what(), kDatabase);
  }
  catch (const Interrupted&)
  {
    return report(command->name, "", "interrupted; nothing half-written was left", kInterrupted);
  }
  catch (const asrt::tools::WriteInterrupted&)
  {
    // Stopped while writing through a FIFO or device, before any file was renamed into place.
    return report(command->name, "", "interrupted; nothing half-written was left", kInterrupted);
  }
  catch (const std::exception& e)
  {
    return report(command->name, "", e.what(), kFailure);
  }
}
