// MPI runs of asrt: VTK's vtkMPIController over the MPI the program was started with (mpirun).
// Built without MPI (no VTK::ParallelMPI or no MPI found at configure time), --mpi is refused.
#include "Cli.h"

#ifdef ASRT_HAVE_MPI
#include "vtkMPI.h"
#include "vtkMPIController.h"
#endif

#include <cstdio>
#include <memory>

namespace asrt
{
namespace cli
{
namespace
{
std::unique_ptr<ParallelRun> active;
bool sharedFailure = false;
}

const ParallelRun* parallelRun()
{
  return active.get();
}

void markSharedFailure()
{
  sharedFailure = true;
}

bool silentParallelFailure()
{
  return active && active->rank != 0 && sharedFailure;
}

#ifdef ASRT_HAVE_MPI
const ParallelRun& startParallelRun()
{
  if (!active)
  {
    auto* controller = vtkMPIController::New();
    controller->Initialize(nullptr, nullptr);
    vtkMultiProcessController::SetGlobalController(controller);
    active = std::make_unique<ParallelRun>();
    active->rank = controller->GetLocalProcessId();
    active->size = controller->GetNumberOfProcesses();
    active->controller = controller;
  }
  return *active;
}

int finishParallelRun(int code)
{
  if (!active)
    return code;
  if (code != kOk && !sharedFailure)
  {
    // The others may be waiting for this process in a collective step: end them all.
    std::fflush(stdout);
    std::fflush(stderr);
    MPI_Abort(MPI_COMM_WORLD, code);
  }
  vtkMultiProcessController::SetGlobalController(nullptr);
  active->controller->Finalize();
  active->controller->Delete();
  active.reset();
  return code;
}
#else
const ParallelRun& startParallelRun()
{
  throw UsageError("--mpi: this asrt was built without MPI (it needs VTK's ParallelMPI module and "
                   "an MPI such as Debian's libopenmpi-dev when configured)");
}

int finishParallelRun(int code)
{
  return code;
}
#endif
}
}
