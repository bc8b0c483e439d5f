// A distributed trace in which one process dies: run under mpirun, it traces and stores a frame
// with vtkGeodesicDistributedSource, and process KILL_RANK kills itself with SIGKILL (no chance
// to clean up, as when a machine is lost) right after its KILL_AFTER-th tile is committed, while
// the others are still streaming theirs. mpirun then ends the job; mpi-fault.sh checks what the
// database shows.
// Usage: mpirun -np N asrtDistributedFault SCENE.json WIDTH HEIGHT CONNINFO KILL_RANK KILL_AFTER
#include "vtkGeodesicDistributedSource.h"

#include "vtkCallbackCommand.h"
#include "vtkMPIController.h"
#include "vtkNew.h"

#include <csignal>
#include <cstdio>
#include <cstdlib>

namespace
{
int killAfter = 0;
int tilesStored = 0;

void onTileStored(vtkObject*, unsigned long, void*, void*)
{
  if (++tilesStored >= killAfter)
    std::raise(SIGKILL);
}
}

int main(int argc, char* argv[])
{
  vtkNew<vtkMPIController> controller;
  controller->Initialize(&argc, &argv);
  if (argc != 7)
  {
    std::fprintf(stderr, "usage: %s SCENE.json WIDTH HEIGHT CONNINFO KILL_RANK KILL_AFTER\n",
                 argv[0]);
    controller->Finalize();
    return 2;
  }
  killAfter = std::atoi(argv[6]);
  vtkNew<vtkGeodesicDistributedSource> source;
  source->SetController(controller);
  source->SetSceneFileName(argv[1]);
  source->SetResolution(std::atoi(argv[2]), std::atoi(argv[3]));
  source->StoreFrameOn();
  source->SetConnectionString(argv[4]);
  source->SetLabel("a process dies");
  vtkNew<vtkCallbackCommand> kill;
  kill->SetCallback(onTileStored);
  if (controller->GetLocalProcessId() == std::atoi(argv[5]))
    source->AddObserver(vtkGeodesicDistributedSource::TileStoredEvent, kill);
  source->Update();
  // Reached only if nobody died: the test expects otherwise.
  std::printf("process %d: the frame was stored as %lld\n", controller->GetLocalProcessId(),
              static_cast<long long>(source->GetFrameId()));
  controller->Finalize();
  return 0;
}
