// Accumulation as a VTK pipeline: a frame traced by vtkGeodesicSource is stored in PostgreSQL by
// vtkGeodesicPostgreSQLWriter, read back by vtkGeodesicPostgreSQLReader and written as a PNG.
// A second reader selects rays with SQL: only those that went at least half-way round the hole
// (image_order >= 1), which draws the hole's secondary images alone.
//
// Usage: asrt_example_postgres_pipeline OUTPUT_DIR [SIZE] [CONNINFO]
// With no CONNINFO: the PG* variables if any is set, else the private server of `asrt db`.
#include "vtkGeodesicPostgreSQLReader.h"
#include "vtkGeodesicPostgreSQLWriter.h"
#include "vtkGeodesicSource.h"

#include "DataFiles.h"

#include "vtkImageData.h"
#include "vtkNew.h"

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

namespace
{
/// The reader's image as a PNG (VTK's PNG writer, into a new temporary renamed into place).
bool writePng(vtkGeodesicPostgreSQLReader* frame, const std::string& file)
{
  try
  {
    asrt::tools::writePng(frame->GetImageOutput(), file);
  }
  catch (const std::exception& e)
  {
    std::fprintf(stderr, "%s\n", e.what());
    return false;
  }
  std::printf("%s\n", file.c_str());
  return true;
}
}

int main(int argc, char* argv[])
{
  if (argc < 2)
  {
    std::fprintf(stderr, "usage: %s OUTPUT_DIR [SIZE] [CONNINFO]\n", argv[0]);
    return 2;
  }
  const std::string out = argv[1];
  const int size = argc > 2 ? std::atoi(argv[2]) : 0;
  const char* conninfo = argc > 3 ? argv[3] : "";

  // Trace the last frame of the mass-ramp movie (Fig. 5, M = 1.2).
  vtkNew<vtkGeodesicSource> source;
  source->SetSceneFileName((std::string(ASRT_DATA_DIR) + "/scenes/fig5-mass-end.json").c_str());
  if (size > 0)
    source->SetResolution(size, size);

  // Store it: the writer takes the hit points (port 1), which carry every ray's record and the
  // frame's parameters. The same frame stored again replaces the old one.
  vtkNew<vtkGeodesicPostgreSQLWriter> writer;
  writer->SetInputConnection(source->GetOutputPort(1));
  writer->SetConnectionString(conninfo);
  writer->SetLabel("example: postgres pipeline");
  writer->ReplaceExistingOn();
  writer->Write();
  if (writer->GetFrameId() < 0)
    return 1; // the source or the writer has said why on stderr
  std::printf("stored as frame %lld\n", static_cast<long long>(writer->GetFrameId()));

  // Read it back: the reader's image is shaded again from the stored rays.
  vtkNew<vtkGeodesicPostgreSQLReader> reader;
  reader->SetConnectionString(conninfo);
  reader->SetFrameId(writer->GetFrameId());
  reader->Update();
  if (reader->GetImageOutput()->GetNumberOfPoints() == 0 || !writePng(reader, out + "/stored.png"))
    return 1;

  // Only the rays that went at least half-way round the hole: SQL over the view rays_v.
  vtkNew<vtkGeodesicPostgreSQLReader> rings;
  rings->SetConnectionString(conninfo);
  rings->SetFrameId(writer->GetFrameId());
  rings->SetPredicate("image_order >= 1");
  rings->Update();
  if (rings->GetImageOutput()->GetNumberOfPoints() == 0 ||
      !writePng(rings, out + "/stored-image-order-1.png"))
    return 1;
  return 0;
}
