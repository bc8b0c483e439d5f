// The VTK side of accumulation: vtkGeodesicSource → vtkGeodesicPostgreSQLWriter → a real
// throwaway server → vtkGeodesicPostgreSQLReader gives back the same frame, bit for bit.
#include "SceneFile.h"
#include "ThrowawayPostgres.h"
#include "TraceAndStore.h"
#include "vtkGeodesicPostgreSQLReader.h"
#include "vtkGeodesicPostgreSQLWriter.h"
#include "vtkGeodesicSource.h"

#include "vtkCommand.h"
#include "vtkDataArray.h"
#include "vtkImageData.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkPolyData.h"

#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace
{
asrt::testing::ThrowawayPostgres& server()
{
  static asrt::testing::ThrowawayPostgres instance;
  return instance;
}

std::string scene(const char* name)
{
  return std::string(ASRT_SOURCE_DIR) + "/Data/scenes/" + name;
}

/// Collects the messages of error events, so that expected errors neither pass unseen nor print.
struct ErrorLog : vtkCommand
{
  static ErrorLog* New() { return new ErrorLog; }
  void Execute(vtkObject*, unsigned long, void* data) override
  {
    this->Messages.emplace_back(data ? static_cast<const char*>(data) : "");
  }
  std::vector<std::string> Messages;
};

/// Every value of every point array and the points, as bit patterns keyed by pixel.
std::map<std::pair<int, int>, std::vector<std::uint64_t>> bitsByPixel(vtkPolyData* hits)
{
  std::map<std::pair<int, int>, std::vector<std::uint64_t>> out;
  vtkPointData* pd = hits->GetPointData();
  vtkDataArray* pixel = pd->GetArray("Pixel");
  for (vtkIdType k = 0; k < hits->GetNumberOfPoints(); ++k)
  {
    std::vector<std::uint64_t> bits;
    auto push = [&](double v)
    {
      std::uint64_t b;
      std::memcpy(&b, &v, sizeof b);
      bits.push_back(b);
    };
    double x[3];
    hits->GetPoint(k, x);
    for (double c : x)
      push(c);
    for (int a = 0; a < pd->GetNumberOfArrays(); ++a)
      if (vtkDataArray* arr = pd->GetArray(a))
        for (int c = 0; c < arr->GetNumberOfComponents(); ++c)
          push(arr->GetComponent(k, c));
    out[{ static_cast<int>(pixel->GetComponent(k, 0)),
          static_cast<int>(pixel->GetComponent(k, 1)) }] = bits;
  }
  return out;
}
}

TEST(StorePipeline, WriteThenReadGivesTheSameFrameBitForBit)
{
  vtkNew<vtkGeodesicSource> source;
  source->SetSceneFileName(scene("fig1-cylinders.json").c_str());
  source->SetResolution(24, 24);
  vtkNew<vtkGeodesicPostgreSQLWriter> writer;
  writer->SetInputConnection(source->GetOutputPort(1));
  writer->SetConnectionString(server().conninfo().c_str());
  writer->SetLabel("it's; \"quoted\" -- label ✓");
  ASSERT_EQ(writer->Write(), 1);
  ASSERT_GE(writer->GetFrameId(), 0);

  vtkNew<vtkGeodesicPostgreSQLReader> reader;
  reader->SetConnectionString(server().conninfo().c_str());
  reader->SetFrameId(writer->GetFrameId());
  reader->Update();
  EXPECT_GE(reader->GetNumberOfFrames(), 1);
  EXPECT_EQ(bitsByPixel(reader->GetHitsOutput()), bitsByPixel(source->GetHitsOutput()));
  // The image is shaded again from the stored colours: identical to the traced one.
  vtkImageData* a = reader->GetImageOutput();
  vtkImageData* b = source->GetImageOutput();
  ASSERT_EQ(a->GetNumberOfPoints(), b->GetNumberOfPoints());
  for (const char* name : { "Colors", "ObjectId", "ImageOrder", "PathLength", "Termination" })
  {
    vtkDataArray* x = a->GetPointData()->GetArray(name);
    vtkDataArray* y = b->GetPointData()->GetArray(name);
    ASSERT_TRUE(x && y) << name;
    for (vtkIdType k = 0; k < x->GetNumberOfTuples(); ++k)
      for (int c = 0; c < x->GetNumberOfComponents(); ++c)
        ASSERT_EQ(x->GetComponent(k, c), y->GetComponent(k, c)) << name << " at " << k;
  }
}

TEST(StorePipeline, DuplicatesAreRefusedUnlessReplaced)
{
  vtkNew<vtkGeodesicSource> source;
  source->SetSceneFileName(scene("fig2-no-hole.json").c_str());
  source->SetResolution(8, 8);
  vtkNew<vtkGeodesicPostgreSQLWriter> writer;
  writer->SetInputConnection(source->GetOutputPort(1));
  writer->SetConnectionString(server().conninfo().c_str());
  ASSERT_EQ(writer->Write(), 1);
  const vtkIdType first = writer->GetFrameId();
  vtkNew<ErrorLog> log;
  writer->AddObserver(vtkCommand::ErrorEvent, log);
  writer->Write(); // the same scene with the same parameters: the same frame
  ASSERT_EQ(log->Messages.size(), 1u);
  EXPECT_NE(log->Messages[0].find("duplicate"), std::string::npos) << log->Messages[0];
  writer->ReplaceExistingOn();
  writer->Write();
  EXPECT_EQ(log->Messages.size(), 1u);
  EXPECT_NE(writer->GetFrameId(), first);
  // A different mass is a different frame.
  source->SetMass(0.5);
  writer->ReplaceExistingOff();
  writer->Write();
  EXPECT_EQ(log->Messages.size(), 1u);
}

TEST(StorePipeline, PredicateSelectsRays)
{
  vtkNew<vtkGeodesicSource> source;
  source->SetSceneFileName(scene("fig1-cylinders.json").c_str());
  source->SetResolution(16, 16);
  source->SetMass(0.8); // a frame of its own
  vtkNew<vtkGeodesicPostgreSQLWriter> writer;
  writer->SetInputConnection(source->GetOutputPort(1));
  writer->SetConnectionString(server().conninfo().c_str());
  ASSERT_EQ(writer->Write(), 1);
  vtkNew<vtkGeodesicPostgreSQLReader> reader;
  reader->SetConnectionString(server().conninfo().c_str());
  reader->SetFrameId(writer->GetFrameId());
  reader->SetPredicate("object_id = 1");
  reader->Update();
  auto expected = bitsByPixel(source->GetHitsOutput());
  vtkDataArray* ids = source->GetHitsOutput()->GetPointData()->GetArray("ObjectId");
  vtkDataArray* pixel = source->GetHitsOutput()->GetPointData()->GetArray("Pixel");
  for (vtkIdType k = 0; k < ids->GetNumberOfTuples(); ++k)
    if (ids->GetComponent(k, 0) != 1)
      expected.erase({ static_cast<int>(pixel->GetComponent(k, 0)),
                       static_cast<int>(pixel->GetComponent(k, 1)) });
  ASSERT_FALSE(expected.empty());
  EXPECT_EQ(bitsByPixel(reader->GetHitsOutput()), expected);
}

TEST(StorePipeline, UnreachableServerIsAClearErrorNotACrash)
{
  vtkNew<vtkGeodesicPostgreSQLReader> reader;
  reader->SetConnectionString(
    "host=/nonexistent-asrt-socket-dir port=5 dbname=x connect_timeout=2");
  vtkNew<ErrorLog> log;
  reader->AddObserver(vtkCommand::ErrorEvent, log);
  reader->Update();
  ASSERT_FALSE(log->Messages.empty());
  EXPECT_EQ(reader->GetNumberOfFrames(), 0);
  EXPECT_EQ(reader->GetHitsOutput()->GetNumberOfPoints(), 0);
}

namespace
{
asrt::SceneDescription fig1Description(int w, int h)
{
  std::ifstream in(scene("fig1-cylinders.json"));
  std::stringstream text;
  text << in.rdbuf();
  asrt::SceneDescription d = asrt::parseSceneWithoutImages(text.str());
  d.camera.width = w;
  d.camera.height = h;
  return d;
}

bool sameRecord(const asrt::RayRecord& a, const asrt::RayRecord& b)
{
  auto same = [](double x, double y) { return std::memcmp(&x, &y, sizeof x) == 0; };
  auto same3 = [&](const asrt::Vec3& x, const asrt::Vec3& y)
  { return same(x[0], y[0]) && same(x[1], y[1]) && same(x[2], y[2]); };
  return a.i == b.i && a.j == b.j && a.termination == b.termination && a.objectId == b.objectId &&
         same3(a.hitPoint, b.hitPoint) && same3(a.hitNormal, b.hitNormal) && same(a.u, b.u) &&
         same(a.v, b.v) && same(a.affineLength, b.affineLength) && same(a.winding, b.winding) &&
         a.imageOrder == b.imageOrder && a.steps == b.steps && same(a.maxAbsH, b.maxAbsH) &&
         same3(a.color, b.color) && same(a.dudi, b.dudi) && same(a.dudj, b.dudj) &&
         same(a.dvdi, b.dvdi) && same(a.dvdj, b.dvdj) && same3(a.origin, b.origin) &&
         same3(a.direction, b.direction) && same(a.momentum[0], b.momentum[0]) &&
         same(a.momentum[3], b.momentum[3]);
}
}

TEST(StorePipeline, StreamedTraceAndStoreStoresExactlyTheTracedFrame)
{
  // Bands traced on one thread while the COPY streams the previous ones must give the very
  // records of a whole-frame trace: the halo rows keep the Jacobians of band edges.
  const asrt::SceneDescription d = fig1Description(21, 17);
  const asrt::FrameTracer tracer(d);
  asrt::RayStore store(server().conninfo());
  store.migrate();
  asrt::TraceAndStoreOptions options;
  options.rowsPerChunk = 4;
  options.label = "streamed";
  const std::int64_t id = asrt::traceAndStore(tracer, store, options);
  const std::vector<asrt::RayRecord> stored = store.readFrame(id);
  const std::vector<asrt::RayRecord> traced = tracer.traceRows(0, 17);
  ASSERT_EQ(stored.size(), traced.size());
  for (size_t k = 0; k < stored.size(); ++k)
    ASSERT_TRUE(sameRecord(stored[k], traced[k])) << "record " << k;
}

TEST(StorePipeline, AbortedTraceAndStoreLeavesNothing)
{
  const asrt::SceneDescription d = fig1Description(16, 16);
  const asrt::FrameTracer tracer(d);
  asrt::RayStore store(server().conninfo());
  store.migrate();
  const size_t before = store.listFrames().size();
  asrt::TraceAndStoreOptions options;
  options.rowsPerChunk = 2;
  options.progress = [](double f) { return f < 0.5; };
  EXPECT_THROW(asrt::traceAndStore(tracer, store, options), std::runtime_error);
  EXPECT_EQ(store.listFrames().size(), before);
  EXPECT_FALSE(store.findFrame(d).has_value());
  // And the same frame stores fine afterwards.
  options.progress = nullptr;
  EXPECT_GE(asrt::traceAndStore(tracer, store, options), 0);
}
