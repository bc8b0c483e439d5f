// Distributed tracing with MPI: every process traces every N-th row of a Kerr frame, all of them
// stream their rows to PostgreSQL as tiles of one frame, and process 0 assembles the picture.
//
// Usage: mpirun -np N asrt_example_distributed_trace OUTPUT_DIR [WIDTH] [CONNINFO]
// The frame is WIDTH x WIDTH*9/16 (default 320 x 180). With a CONNINFO ("" for the PG*
// variables, else the private server of `asrt db`) the frame is stored; without, it is not.
// Give every process its own threads: OMP_NUM_THREADS=1 mpirun -np 2 ... on a 2-core machine.
#include "vtkGeodesicDistributedSource.h"

#include "vtkDoubleArray.h"
#include "vtkExecutive.h"
#include "vtkImageData.h"
#include "vtkMPIController.h"
#include "vtkNew.h"
#include "vtkPNGWriter.h"

#include <cstdio>
#include <cstdlib>
#include <string>

int main(int argc, char* argv[])
{
  // MPI first: every process runs this program; the controller says which one this is.
  vtkNew<vtkMPIController> controller;
  controller->Initialize(&argc, &argv);
  vtkMultiProcessController::SetGlobalController(controller);
  const int rank = controller->GetLocalProcessId();
  int status = 0;
  if (argc < 2)
  {
    if (rank == 0)
      std::fprintf(stderr, "usage: mpirun -np N %s OUTPUT_DIR [WIDTH] [CONNINFO]\n", argv[0]);
    status = 2;
  }
  else
  {
    const std::string out = argv[1];
    const int width = argc > 2 ? std::atoi(argv[2]) : 320;

    vtkNew<vtkGeodesicDistributedSource> source;
    source->SetController(controller);
    source->SetSceneFileName((std::string(ASRT_DATA_DIR) + "/scenes/kerr-disk.json").c_str());
    source->SetResolution(width, width * 9 / 16);
    if (argc > 3)
    {
      source->StoreFrameOn();
      source->SetConnectionString(argv[3]);
      source->SetLabel("example: distributed trace");
      source->ReplaceExistingOn();
    }
    // Collective: every process updates; on failure every process reports the same error.
    const bool traced = source->GetExecutive()->Update(0) != 0;
    if (!traced)
      status = 1; // the source said why on stderr
    else if (rank == 0)
    {
      vtkImageData* image = source->GetImageOutput();
      vtkNew<vtkPNGWriter> png;
      png->SetInputData(image);
      png->SetFileName((out + "/kerr-disk-distributed.png").c_str());
      png->Write();
      std::printf("%s/kerr-disk-distributed.png\n", out.c_str());
      if (source->GetFrameId() >= 0)
        std::printf("stored as frame %lld\n", static_cast<long long>(source->GetFrameId()));
      // The load balance: integration steps and time of every process.
      vtkDoubleArray* work = source->GetRankWork();
      for (vtkIdType p = 0; p < work->GetNumberOfTuples(); ++p)
        std::printf("process %lld: %.0f steps, %.0f rays, %.2f s tracing, %.2f s storing\n",
                    static_cast<long long>(p), work->GetComponent(p, 0), work->GetComponent(p, 1),
                    work->GetComponent(p, 2), work->GetComponent(p, 3));
      status = png->GetErrorCode() == 0 ? 0 : 1;
    }
  }
  vtkMultiProcessController::SetGlobalController(nullptr);
  controller->Finalize();
  return status;
}
