// The VTK side of accumulation: vtkGeodesicSource → vtkGeodesicPostgreSQLWriter → a real
// throwaway server → vtkGeodesicPostgreSQLReader gives back the same frame, bit for bit.
#include "FrameTracer.h"
#include "GeodesicSceneLoading.h"
#include "SceneFile.h"
#include "StoreTestSupport.h"
#include "ThrowawayPostgres.h"
#include "TraceAndStore.h"
#include "vtkGeodesicPostgreSQLReader.h"
#include "vtkGeodesicPostgreSQLWriter.h"
#include "vtkGeodesicSource.h"

#include "vtkCellArray.h"
#include "vtkCellData.h"
#include "vtkCommand.h"
#include "vtkDataArray.h"
#include "vtkImageData.h"
#include "vtkIntArray.h"
#include "vtkNew.h"
#include "vtkPointData.h"
#include "vtkPolyData.h"
#include "vtkSmartPointer.h"
#include "vtkUnsignedCharArray.h"

#include <algorithm>
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
  for (const char* name :
       { "Colors", "ObjectId", "ImageOrder", "PathLength", "Termination", "RaysPerPixel" })
  {
    vtkDataArray* x = a->GetPointData()->GetArray(name);
    vtkDataArray* y = b->GetPointData()->GetArray(name);
    ASSERT_TRUE(x && y) << name;
    for (vtkIdType k = 0; k < x->GetNumberOfTuples(); ++k)
      for (int c = 0; c < x->GetNumberOfComponents(); ++c)
        ASSERT_EQ(x->GetComponent(k, c), y->GetComponent(k, c)) << name << " at " << k;
  }
}

TEST(StorePipeline, AFrameTheWriterStreamsOverSeveralConnectionsIsTheSameBitForBit)
{
  // Large enough for two tiles of at least RayStore::kParallelMinRays rays: the writer reads the
  // hit points from two threads at once.
  vtkNew<vtkGeodesicSource> source;
  source->SetSceneFileName(scene("fig1-cylinders.json").c_str());
  source->SetResolution(384, 352);
  vtkNew<vtkGeodesicPostgreSQLWriter> writer;
  writer->SetInputConnection(source->GetOutputPort(1));
  writer->SetConnectionString(server().conninfo().c_str());
  writer->SetLabel("two tiles");
  ASSERT_EQ(writer->Write(), 1);
  asrt::RayStore store(server().conninfo());
  EXPECT_EQ(store.frameInfo(writer->GetFrameId()).tileCount, 2);
  vtkNew<vtkGeodesicPostgreSQLReader> reader;
  reader->SetConnectionString(server().conninfo().c_str());
  reader->SetFrameId(writer->GetFrameId());
  reader->Update();
  EXPECT_EQ(bitsByPixel(reader->GetHitsOutput()), bitsByPixel(source->GetHitsOutput()));
}

TEST(StorePipeline, RaysPerPixelGoThroughTheWriterAndTheReader)
{
  vtkNew<vtkGeodesicSource> source;
  source->SetSceneFileName(scene("fig2-no-hole.json").c_str());
  source->SetResolution(6, 5);
  source->SetAntialias("none");
  source->Update();
  vtkIntArray* traced =
    vtkIntArray::SafeDownCast(source->GetHitsOutput()->GetPointData()->GetArray("RaysPerPixel"));
  ASSERT_TRUE(traced);
  // Anti-aliasing "none": one ray a pixel.
  for (vtkIdType k = 0; k < traced->GetNumberOfTuples(); ++k)
    ASSERT_EQ(traced->GetValue(k), 1) << k;
  vtkNew<vtkPolyData> hits;
  hits->DeepCopy(source->GetHitsOutput());
  vtkIntArray* counts = vtkIntArray::SafeDownCast(hits->GetPointData()->GetArray("RaysPerPixel"));
  const int given[] = { 1, 9, 1024 };
  for (vtkIdType k = 0; k < counts->GetNumberOfTuples(); ++k)
    counts->SetValue(k, given[k % 3]);
  vtkNew<vtkGeodesicPostgreSQLWriter> writer;
  writer->SetInputData(hits);
  writer->SetConnectionString(server().conninfo().c_str());
  ASSERT_EQ(writer->Write(), 1);
  vtkNew<vtkGeodesicPostgreSQLReader> reader;
  reader->SetConnectionString(server().conninfo().c_str());
  reader->SetFrameId(writer->GetFrameId());
  reader->Update();
  EXPECT_EQ(bitsByPixel(reader->GetHitsOutput()), bitsByPixel(hits));
  vtkDataArray* pixel = hits->GetPointData()->GetArray("Pixel");
  vtkIntArray* image =
    vtkIntArray::SafeDownCast(reader->GetImageOutput()->GetPointData()->GetArray("RaysPerPixel"));
  ASSERT_TRUE(image);
  for (vtkIdType k = 0; k < counts->GetNumberOfTuples(); ++k)
  {
    const auto at =
      static_cast<vtkIdType>(pixel->GetComponent(k, 1) * 6 + pixel->GetComponent(k, 0));
    EXPECT_EQ(image->GetValue(at), given[k % 3]) << "pixel " << at;
  }

  // Hit points without the array, made before anti-aliasing, were traced one ray a pixel.
  const vtkIdType n = counts->GetNumberOfTuples();
  hits->GetPointData()->RemoveArray("RaysPerPixel");
  writer->ReplaceExistingOn();
  ASSERT_EQ(writer->Write(), 1);
  reader->SetFrameId(writer->GetFrameId());
  reader->Update();
  vtkDataArray* read = reader->GetHitsOutput()->GetPointData()->GetArray("RaysPerPixel");
  ASSERT_TRUE(read);
  ASSERT_EQ(read->GetNumberOfTuples(), n);
  for (vtkIdType k = 0; k < read->GetNumberOfTuples(); ++k)
    EXPECT_EQ(read->GetComponent(k, 0), 1) << k;
}

// The adaptive grid fills smooth blocks with interpolated records: each record's "Traced" flag
// goes through the writer, the store and the reader as the source traced it.
TEST(StorePipeline, TracedFlagsOfTheAdaptiveGridGoThroughTheWriterAndTheReader)
{
  vtkNew<vtkGeodesicSource> source;
  source->SetSceneFileName(scene("fig1-cylinders.json").c_str());
  source->SetResolution(48, 36);
  source->SetAntialias("none");
  source->SetGridLattice(8);
  source->Update();
  vtkPolyData* traced = source->GetHitsOutput();
  auto* flags = vtkUnsignedCharArray::SafeDownCast(traced->GetPointData()->GetArray("Traced"));
  ASSERT_TRUE(flags);
  ASSERT_EQ(flags->GetNumberOfTuples(), 48 * 36);
  std::map<std::pair<int, int>, int> byPixel;
  vtkDataArray* pixel = traced->GetPointData()->GetArray("Pixel");
  int interpolated = 0;
  for (vtkIdType k = 0; k < flags->GetNumberOfTuples(); ++k)
  {
    ASSERT_LE(flags->GetValue(k), 1) << k;
    interpolated += flags->GetValue(k) == 0;
    byPixel[{ int(pixel->GetComponent(k, 0)), int(pixel->GetComponent(k, 1)) }] =
      flags->GetValue(k);
  }
  ASSERT_GT(interpolated, 0) << "the grid interpolated no record";
  ASSERT_LT(interpolated, flags->GetNumberOfTuples()) << "the grid traced no record";

  vtkNew<vtkGeodesicPostgreSQLWriter> writer;
  writer->SetInputConnection(source->GetOutputPort(1));
  writer->SetConnectionString(server().conninfo().c_str());
  ASSERT_EQ(writer->Write(), 1);
  vtkNew<vtkGeodesicPostgreSQLReader> reader;
  reader->SetConnectionString(server().conninfo().c_str());
  reader->SetFrameId(writer->GetFrameId());
  reader->Update();
  EXPECT_EQ(bitsByPixel(reader->GetHitsOutput()), bitsByPixel(traced));
  vtkPolyData* read = reader->GetHitsOutput();
  auto* readFlags = vtkUnsignedCharArray::SafeDownCast(read->GetPointData()->GetArray("Traced"));
  ASSERT_TRUE(readFlags);
  vtkDataArray* readPixel = read->GetPointData()->GetArray("Pixel");
  int readInterpolated = 0;
  for (vtkIdType k = 0; k < readFlags->GetNumberOfTuples(); ++k)
  {
    const std::pair<int, int> ij(int(readPixel->GetComponent(k, 0)),
                                 int(readPixel->GetComponent(k, 1)));
    EXPECT_EQ(int(readFlags->GetValue(k)), byPixel.at(ij)) << ij.first << ", " << ij.second;
    readInterpolated += readFlags->GetValue(k) == 0;
  }
  EXPECT_EQ(readInterpolated, interpolated);
  // The store itself, without the filters: the records' flags.
  asrt::RayStore store(server().conninfo());
  int stored = 0;
  for (const asrt::RayRecord& r : store.readFrame(writer->GetFrameId()))
  {
    EXPECT_EQ(r.traced ? 1 : 0, byPixel.at({ r.i, r.j })) << r.i << ", " << r.j;
    stored += !r.traced;
  }
  EXPECT_EQ(stored, interpolated);
}

// Hit points made before the adaptive grid have no "Traced" array: every ray of theirs was
// traced. A value other than 0 or 1 is refused, naming the array.
TEST(StorePipeline, HitPointsWithoutTracedFlagsWereTracedAndBadFlagsAreRefused)
{
  vtkNew<vtkGeodesicSource> source;
  source->SetSceneFileName(scene("fig2-no-hole.json").c_str());
  source->SetResolution(7, 5);
  source->SetAntialias("none");
  source->Update();
  vtkNew<vtkPolyData> hits;
  hits->DeepCopy(source->GetHitsOutput());
  hits->GetPointData()->RemoveArray("Traced");
  vtkNew<vtkGeodesicPostgreSQLWriter> writer;
  writer->SetInputData(hits);
  writer->SetConnectionString(server().conninfo().c_str());
  writer->SetLabel("no traced flags");
  ASSERT_EQ(writer->Write(), 1);
  asrt::RayStore store(server().conninfo());
  const std::vector<asrt::RayRecord> records = store.readFrame(writer->GetFrameId());
  ASSERT_EQ(records.size(), std::size_t(35));
  for (const asrt::RayRecord& r : records)
    EXPECT_TRUE(r.traced) << r.i << ", " << r.j;

  vtkNew<vtkPolyData> bad;
  bad->DeepCopy(source->GetHitsOutput());
  vtkDataArray* flags = bad->GetPointData()->GetArray("Traced");
  ASSERT_TRUE(flags);
  flags->SetComponent(3, 0, 2);
  vtkNew<vtkGeodesicPostgreSQLWriter> refusing;
  refusing->SetInputData(bad);
  refusing->SetConnectionString(server().conninfo().c_str());
  refusing->SetLabel("bad traced flags");
  refusing->ReplaceExistingOn();
  vtkNew<ErrorLog> log;
  refusing->AddObserver(vtkCommand::ErrorEvent, log);
  refusing->Write();
  ASSERT_EQ(log->Messages.size(), 1u);
  EXPECT_NE(log->Messages.front().find("\"Traced\""), std::string::npos) << log->Messages.front();
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

// -----------------------------------------------------------------------------------------------
// The source's polylines, stored with the frame.

namespace
{
/// Everything a polyline output holds, as bits: per line its cell values and its points with
/// their point values, in order.
std::vector<std::vector<std::uint64_t>> lineBits(vtkPolyData* lines)
{
  std::vector<std::vector<std::uint64_t>> out;
  auto bits = [](double v)
  {
    std::uint64_t b;
    std::memcpy(&b, &v, sizeof b);
    return b;
  };
  vtkCellArray* cells = lines->GetLines();
  vtkNew<vtkIdList> ids;
  for (vtkIdType c = 0; c < lines->GetNumberOfLines(); ++c)
  {
    std::vector<std::uint64_t> line;
    for (const char* name : { "Pixel", "Termination" })
    {
      vtkDataArray* a = lines->GetCellData()->GetArray(name);
      for (int k = 0; k < a->GetNumberOfComponents(); ++k)
        line.push_back(bits(a->GetComponent(c, k)));
    }
    cells->GetCellAtId(c, ids);
    for (vtkIdType m = 0; m < ids->GetNumberOfIds(); ++m)
    {
      const vtkIdType p = ids->GetId(m);
      double x[3];
      lines->GetPoint(p, x);
      for (double v : x)
        line.push_back(bits(v));
      for (const char* name : { "Lambda", "R", "AbsH" })
        line.push_back(bits(lines->GetPointData()->GetArray(name)->GetComponent(p, 0)));
    }
    out.push_back(line);
  }
  return out;
}

/// A value from the database, whose schema exists (each test may run alone in its process).
/// vtkGeodesicSource tracing fig1 at w × h with polylines every `stride` pixels, and a writer of
/// its hits and polylines to the test server.
struct PolylineFrame
{
  PolylineFrame(int w, int h, int stride)
  {
    this->Source->SetSceneFileName(scene("fig1-cylinders.json").c_str());
    this->Source->SetResolution(w, h);
    this->Source->GeneratePolylinesOn();
    this->Source->SetPolylineStride(stride);
    this->Writer->SetInputConnection(0, this->Source->GetOutputPort(1));
    this->Writer->SetInputConnection(1, this->Source->GetOutputPort(2));
    this->Writer->SetConnectionString(server().conninfo().c_str());
  }
  vtkNew<vtkGeodesicSource> Source;
  vtkNew<vtkGeodesicPostgreSQLWriter> Writer;
};

std::string count(const std::string& sql)
{
  asrt::RayStore(server().conninfo()).migrate();
  return asrt::testing::Db(server().conninfo()).value(sql);
}
}

TEST(StorePipeline, PolylinesRoundTripBitForBit)
{
  PolylineFrame frame(12, 9, 4);
  vtkGeodesicSource* source = frame.Source;
  vtkGeodesicPostgreSQLWriter* writer = frame.Writer;
  source->SetMass(0.9); // a frame of its own
  ASSERT_EQ(writer->Write(), 1);
  vtkPolyData* traced = source->GetPolylinesOutput();
  ASSERT_EQ(traced->GetNumberOfLines(), 9); // pixels (0|4|8, 0|4|8)
  ASSERT_GT(traced->GetNumberOfPoints(), 9 * 10);

  vtkNew<vtkGeodesicPostgreSQLReader> reader;
  reader->SetConnectionString(server().conninfo().c_str());
  reader->SetFrameId(writer->GetFrameId());
  reader->Update();
  EXPECT_EQ(lineBits(reader->GetPolylinesOutput()), lineBits(traced));
  EXPECT_EQ(bitsByPixel(reader->GetHitsOutput()), bitsByPixel(source->GetHitsOutput()));
  // SQL sees every point.
  EXPECT_EQ(count("SELECT count(*) FROM path_points_v WHERE frame_id = " +
                  std::to_string(writer->GetFrameId())),
            std::to_string(traced->GetNumberOfPoints()));

  // With a predicate, the polylines of the selected rays' pixels only.
  reader->SetPredicate("i = 4");
  reader->Update();
  const auto all = lineBits(traced);
  std::vector<std::vector<std::uint64_t>> expected;
  vtkDataArray* pixel = traced->GetCellData()->GetArray("Pixel");
  for (vtkIdType c = 0; c < traced->GetNumberOfLines(); ++c)
    if (pixel->GetComponent(c, 0) == 4)
      expected.push_back(all[static_cast<size_t>(c)]);
  ASSERT_EQ(expected.size(), 3u);
  EXPECT_EQ(lineBits(reader->GetPolylinesOutput()), expected);

  // A frame written without polylines reads back with none.
  vtkNew<vtkGeodesicPostgreSQLWriter> bare;
  source->SetMass(0.95);
  bare->SetInputConnection(0, source->GetOutputPort(1));
  bare->SetConnectionString(server().conninfo().c_str());
  ASSERT_EQ(bare->Write(), 1);
  reader->SetPredicate(nullptr);
  reader->SetFrameId(bare->GetFrameId());
  reader->Update();
  EXPECT_EQ(reader->GetPolylinesOutput()->GetNumberOfLines(), 0);
  EXPECT_GT(reader->GetHitsOutput()->GetNumberOfPoints(), 0);
}

TEST(StorePipeline, PolylinesAndRaysAreWrittenTogetherOrNotAtAll)
{
  PolylineFrame frame(13, 11, 5); // 143 rays, which the veto below refuses
  vtkGeodesicSource* source = frame.Source;
  vtkGeodesicPostgreSQLWriter* writer = frame.Writer;
  vtkNew<ErrorLog> log;
  writer->AddObserver(vtkCommand::ErrorEvent, log);
  const std::string state = "SELECT (SELECT count(*) FROM frames) || ':' || (SELECT count(*) FROM "
                            "ray_paths) || ':' || (SELECT count(*) FROM ray_blocks)";
  const std::string before = count(state);
  // The server refuses the transaction's last statement, after the rays and the polylines.
  asrt::testing::Db db(server().conninfo());
  db.value("ALTER TABLE frame_tiles ADD CONSTRAINT veto CHECK (ray_count <> 143)");
  writer->Write();
  db.value("ALTER TABLE frame_tiles DROP CONSTRAINT veto");
  ASSERT_EQ(log->Messages.size(), 1u);
  EXPECT_NE(log->Messages[0].find("veto"), std::string::npos) << log->Messages[0];
  EXPECT_EQ(count(state), before);
  // Then it goes in whole.
  writer->Write();
  EXPECT_EQ(log->Messages.size(), 1u);
  vtkNew<vtkGeodesicPostgreSQLReader> reader;
  reader->SetConnectionString(server().conninfo().c_str());
  reader->SetFrameId(writer->GetFrameId());
  reader->Update();
  EXPECT_EQ(lineBits(reader->GetPolylinesOutput()), lineBits(source->GetPolylinesOutput()));
}

TEST(StorePipeline, BadPolylinesAreRefusedBeforeAnythingIsWritten)
{
  vtkNew<vtkGeodesicSource> source;
  source->SetSceneFileName(scene("fig2-no-hole.json").c_str());
  source->SetResolution(10, 10);
  source->SetMass(0.7);
  source->GeneratePolylinesOn();
  vtkNew<vtkIntArray> twice; // one pixel listed twice: two polylines of one pixel
  twice->SetNumberOfComponents(2);
  for (int k = 0; k < 2; ++k)
    twice->InsertNextTuple2(3, 4);
  source->SetPolylinePixels(twice);
  source->Update();
  vtkPolyData* good = source->GetPolylinesOutput();
  ASSERT_EQ(good->GetNumberOfLines(), 2);

  auto variant = [&](auto change)
  {
    auto copy = vtkSmartPointer<vtkPolyData>::New();
    copy->DeepCopy(good);
    change(copy.Get());
    return copy;
  };
  struct Case
  {
    const char* what;
    vtkSmartPointer<vtkPolyData> lines;
    const char* message;
  };
  const Case cases[] = {
    { "duplicate pixel", variant([](vtkPolyData*) {}), "that pixel already has a path" },
    { "no Lambda", variant([](vtkPolyData* p) { p->GetPointData()->RemoveArray("Lambda"); }),
      "\"Lambda\" point array" },
    { "no Pixel", variant([](vtkPolyData* p) { p->GetCellData()->RemoveArray("Pixel"); }),
      "\"Pixel\" cell array" },
    { "pixel outside",
      variant([](vtkPolyData* p) { p->GetCellData()->GetArray("Pixel")->SetComponent(1, 0, 10); }),
      "lies outside the 10 x 10 frame" },
    { "bad termination",
      variant([](vtkPolyData* p)
              { p->GetCellData()->GetArray("Termination")->SetComponent(0, 0, 99); }),
      "unknown termination 99" },
    { "a vertex",
      variant(
        [](vtkPolyData* p)
        {
          p->GetCellData()->Initialize(); // only the lines' cell data would be valid
          vtkNew<vtkCellArray> verts;
          const vtkIdType zero = 0;
          verts->InsertNextCell(1, &zero);
          p->SetVerts(verts);
        }),
      "not lines" },
  };
  const std::string state = "SELECT (SELECT count(*) FROM frames) || ':' || (SELECT count(*) FROM "
                            "ray_paths) || ':' || (SELECT count(*) FROM scenes)";
  const std::string before = count(state);
  for (const Case& c : cases)
  {
    vtkNew<vtkGeodesicPostgreSQLWriter> writer;
    writer->SetInputConnection(0, source->GetOutputPort(1));
    writer->SetInputData(1, c.lines);
    writer->SetConnectionString(server().conninfo().c_str());
    vtkNew<ErrorLog> log;
    writer->AddObserver(vtkCommand::ErrorEvent, log);
    writer->Write();
    ASSERT_EQ(log->Messages.size(), 1u) << c.what;
    EXPECT_NE(log->Messages[0].find(c.message), std::string::npos)
      << c.what << ": " << log->Messages[0];
    EXPECT_EQ(writer->GetFrameId(), -1) << c.what;
    EXPECT_EQ(count(state), before) << c.what;
  }
}

TEST(StorePipeline, AFrameRowEditedToAnImpossibleSizeIsAnErrorNotAnAllocation)
{
  const asrt::SceneDescription d = fig1Description(8, 6);
  const asrt::FrameTracer tracer(d);
  asrt::RayStore store(server().conninfo());
  store.migrate();
  asrt::TraceAndStoreOptions options;
  options.label = "edited size";
  const std::int64_t id = asrt::traceAndStore(tracer, store, options);
  asrt::testing::Db db(server().conninfo());
  const std::string where = " WHERE id = " + std::to_string(id);
  const std::string frame = "frame " + std::to_string(id) + " is inconsistent: ";

  auto readError = [&](double memoryLimit)
  {
    vtkNew<vtkGeodesicPostgreSQLReader> reader;
    reader->SetConnectionString(server().conninfo().c_str());
    reader->SetFrameId(id);
    reader->SetMemoryLimit(memoryLimit);
    vtkNew<ErrorLog> log;
    reader->AddObserver(vtkCommand::ErrorEvent, log);
    reader->Update();
    if (log->Messages.empty())
    {
      EXPECT_EQ(reader->GetImageOutput()->GetNumberOfPoints(), 8 * 6);
      return std::string("(no error)");
    }
    EXPECT_EQ(reader->GetImageOutput()->GetNumberOfPoints(), 0);
    EXPECT_EQ(reader->GetHitsOutput()->GetNumberOfPoints(), 0);
    return log->Messages[0];
  };
  for (const char* size : { "width = 100000, height = 100000", "width = 2147483647, height = 1" })
  {
    db.value(std::string("UPDATE frames SET ") + size + where);
    const std::string e = readError(0);
    EXPECT_NE(e.find(frame + "frames.width x frames.height = "), std::string::npos) << size << e;
  }
  db.value("UPDATE frames SET width = 8, height = 0" + where);
  EXPECT_NE(readError(0).find(frame + "frames.height = 0"), std::string::npos);

  // Within the pixel limit, but more than the memory allowed.
  db.value("UPDATE frames SET width = 8, height = 6" + where);
  EXPECT_EQ(readError(0), "(no error)");
  const std::string e = readError(1000);
  EXPECT_NE(e.find("frame " + std::to_string(id) + " (8 x 6 pixels, 48 rays) needs about"),
            std::string::npos)
    << e;
}
