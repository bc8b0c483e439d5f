// Traces a scene file to a PNG image, optionally writing the hit records to a VTK XML file and
// accumulating the frame in PostgreSQL.
// Usage: asrt_trace_scene scene.json out.png [width height] [hits.vtp] [--store[=label]]
// With --store the frame is traced straight into the store (the COPY streams while later rows are
// traced): PG* variables if set, else the private embedded server (see asrt_db).
#include "vtkGeodesicPostgreSQLReader.h"
#include "vtkGeodesicSource.h"

#include "RayStore.h"
#include "StoreConnection.h"
#include "TraceAndStore.h"

#include "vtkImageData.h"
#include "vtkNew.h"
#include "vtkPNGWriter.h"
#include "vtkSmartPointer.h"
#include "vtkXMLPolyDataWriter.h"

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

int main(int argc, char* argv[])
{
  std::vector<std::string> args;
  bool store = false;
  std::string label;
  for (int k = 1; k < argc; ++k)
  {
    if (std::strncmp(argv[k], "--store", 7) == 0)
    {
      store = true;
      if (argv[k][7] == '=')
        label = argv[k] + 8;
    }
    else
      args.emplace_back(argv[k]);
  }
  if (args.size() < 2)
  {
    std::fprintf(stderr,
                 "usage: %s scene.json out.png [width height] [hits.vtp] [--store[=label]]\n",
                 argv[0]);
    return 2;
  }
  const int width = args.size() >= 4 ? std::atoi(args[2].c_str()) : 0;
  const int height = args.size() >= 4 ? std::atoi(args[3].c_str()) : 0;
  const auto t0 = std::chrono::steady_clock::now();
  vtkSmartPointer<vtkAlgorithm> frame;
  if (store)
  {
    // Trace straight into the store (the COPY streams while later rows are traced), then read the
    // frame back from the database for the image: the accumulation's round trip.
    try
    {
      asrt::SceneDescription d =
        asrt::loadSceneFile(args[0],
                            [](const std::string& path)
                            {
                              asrt::ImagePixels px;
                              vtkGeodesicSource::LoadImagePixels(path, px.width, px.height, px.rgb);
                              return px;
                            });
      if (width > 0 && height > 0)
      {
        d.camera.width = width;
        d.camera.height = height;
      }
      const asrt::FrameTracer tracer(d);
      const std::string conninfo = asrt::storeConnection(std::getenv("ASRT_DB"));
      asrt::RayStore db(conninfo);
      db.migrate();
      asrt::TraceAndStoreOptions options;
      options.label = label;
      options.replace = true;
      const std::int64_t id = asrt::traceAndStore(tracer, db, options);
      std::printf("%s: traced and stored as frame %lld\n", args[0].c_str(),
                  static_cast<long long>(id));
      auto reader = vtkSmartPointer<vtkGeodesicPostgreSQLReader>::New();
      reader->SetConnectionString(conninfo.c_str());
      reader->SetFrameId(static_cast<vtkIdType>(id));
      frame = reader;
    }
    catch (const std::exception& e)
    {
      std::fprintf(stderr, "asrt_trace_scene: storing failed: %s\n", e.what());
      return 1;
    }
  }
  else
  {
    auto source = vtkSmartPointer<vtkGeodesicSource>::New();
    source->SetSceneFileName(args[0].c_str());
    if (width > 0 && height > 0)
      source->SetResolution(width, height);
    frame = source;
  }
  frame->Update();
  const double seconds =
    std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  vtkImageData* image = vtkImageData::SafeDownCast(frame->GetOutputDataObject(0));
  if (!image || image->GetNumberOfPoints() == 0)
    return 1; // the algorithm has reported why
  vtkNew<vtkPNGWriter> png;
  png->SetInputConnection(frame->GetOutputPort(0));
  png->SetFileName(args[1].c_str());
  png->Write();
  if (args.size() >= 5)
  {
    vtkNew<vtkXMLPolyDataWriter> hits;
    hits->SetInputConnection(frame->GetOutputPort(1));
    hits->SetFileName(args[4].c_str());
    hits->Write();
  }
  int dims[3];
  image->GetDimensions(dims);
  std::printf("%s: %d x %d in %.2f s -> %s\n", args[0].c_str(), dims[0], dims[1], seconds,
              args[1].c_str());
  return 0;
}
