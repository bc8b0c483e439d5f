// Exact mode accumulates its re-traced rays in a real (throwaway) PostgreSQL server: as a subset
// frame of its own that never collides with the whole frame at the same parameters, read back
// instead of traced again by a later request.
#include "InterpolationTestSupport.h"

#include "FrameInterpolation.h"
#include "RayStore.h"
#include "ThrowawayPostgres.h"
#include "vtkGeodesicPostgreSQLWriter.h"

using namespace asrt::testing;

namespace
{
ThrowawayPostgres& server()
{
  static ThrowawayPostgres instance;
  return instance;
}

TracedFrame rampFrame(double mass)
{
  return traceWith(
    [mass](vtkGeodesicSource* s)
    {
      s->SetSceneFileName(scenePath("fig4-mass-start.json").c_str());
      s->SetResolution(48, 48);
      s->SetMass(mass);
    });
}

struct ExactRun
{
  vtkSmartPointer<vtkImageData> image;
  vtkIdType retraced = 0, reused = 0, frameId = -1;
  std::vector<std::string> errors;
};

ExactRun exactFrame(const TracedFrame& a, const TracedFrame& b, const std::string& conninfo)
{
  auto pa = producerOf(a.hits), pb = producerOf(b.hits);
  vtkNew<vtkGeodesicFrameInterpolator> interp;
  vtkNew<MessageCatcher> catcher;
  watch(interp, catcher);
  interp->SetFrameAConnection(pa->GetOutputPort());
  interp->SetFrameBConnection(pb->GetOutputPort());
  interp->SetTextureDirectory((std::string(ASRT_SOURCE_DIR) + "/Data/scenes").c_str());
  interp->ExactModeOn();
  interp->StoreRetracedRaysOn();
  interp->SetConnectionString(conninfo.c_str());
  interp->UpdateTimeStep(0.5);
  ExactRun r;
  r.image = vtkSmartPointer<vtkImageData>::New();
  r.image->DeepCopy(interp->GetOutput());
  r.retraced = interp->GetLastRetracedCount();
  r.reused = interp->GetLastReusedCount();
  r.frameId = interp->GetLastStoredFrameId();
  r.errors = catcher->Errors;
  return r;
}
}

TEST(InterpolationStore, ExactModeAccumulatesItsRays)
{
  const TracedFrame a = rampFrame(0.1), b = rampFrame(0.3);
  const ExactRun first = exactFrame(a, b, server().conninfo());
  ASSERT_TRUE(first.errors.empty()) << first.errors.front();
  ASSERT_GT(first.retraced, 0);
  EXPECT_EQ(first.reused, 0);
  ASSERT_GE(first.frameId, 0);

  asrt::RayStore store(server().conninfo());
  std::vector<asrt::FrameInfo> frames = store.listFrames();
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(frames[0].id, first.frameId);
  EXPECT_EQ(frames[0].rayCount, first.retraced);
  EXPECT_EQ(frames[0].label, "interpolation re-trace");
  EXPECT_DOUBLE_EQ(frames[0].key.spacetime.mass, 0.2);
  EXPECT_NE(store.frameSceneText(first.frameId).find("\"subset\""), std::string::npos);

  // The stored rays are the re-traced pixels, with the colours the frame shows there.
  const std::vector<asrt::RayRecord> records = store.readFrame(first.frameId);
  ASSERT_EQ(static_cast<vtkIdType>(records.size()), first.retraced);
  vtkDataArray* cls = first.image->GetPointData()->GetArray("InterpolationClass");
  const auto rgb = rgbOf(first.image);
  std::vector<bool> stored(static_cast<std::size_t>(cls->GetNumberOfTuples()), false);
  for (const asrt::RayRecord& r : records)
  {
    const std::size_t p = static_cast<std::size_t>(r.j) * 48 + static_cast<std::size_t>(r.i);
    stored[p] = true;
    EXPECT_EQ(cls->GetComponent(static_cast<vtkIdType>(p), 0),
              static_cast<int>(asrt::PixelClass::Retraced));
    const auto c = asrt::imageColor(r.color);
    for (int k = 0; k < 3; ++k)
      EXPECT_EQ(rgb[3 * p + k], c[static_cast<std::size_t>(k)]) << "pixel " << p;
  }
  for (vtkIdType p = 0; p < cls->GetNumberOfTuples(); ++p)
  {
    if (cls->GetComponent(p, 0) == static_cast<int>(asrt::PixelClass::Retraced))
    {
      EXPECT_TRUE(stored[static_cast<std::size_t>(p)]) << "re-traced pixel " << p << " not stored";
    }
  }

  // The whole frame at the same parameters is a frame of its own: no collision.
  vtkNew<vtkGeodesicSource> whole;
  whole->SetSceneFileName(scenePath("fig4-mass-start.json").c_str());
  whole->SetResolution(48, 48);
  whole->SetMass(0.2);
  vtkNew<vtkGeodesicPostgreSQLWriter> writer;
  vtkNew<MessageCatcher> writerErrors;
  watch(writer, writerErrors);
  writer->SetInputConnection(whole->GetOutputPort(1));
  writer->SetConnectionString(server().conninfo().c_str());
  ASSERT_EQ(writer->Write(), 1);
  EXPECT_TRUE(writerErrors->Errors.empty()) << writerErrors->AllErrors();
  EXPECT_NE(writer->GetFrameId(), first.frameId);
  frames = store.listFrames();
  ASSERT_EQ(frames.size(), 2u);

  // A later request for the same frame reads the rays back instead of tracing them.
  const ExactRun second = exactFrame(a, b, server().conninfo());
  ASSERT_TRUE(second.errors.empty()) << second.errors.front();
  EXPECT_EQ(second.reused, first.retraced);
  EXPECT_EQ(second.retraced, first.retraced);
  EXPECT_EQ(second.frameId, first.frameId);
  EXPECT_EQ(store.listFrames().size(), 2u);
  EXPECT_EQ(rgbOf(second.image), rgb);
}

TEST(InterpolationStore, BrokenConnectionIsAClearError)
{
  const TracedFrame a = rampFrame(0.1), b = rampFrame(0.3);
  const ExactRun r =
    exactFrame(a, b, "host=/nonexistent-asrt-socket-dir dbname=asrt connect_timeout=2");
  ASSERT_FALSE(r.errors.empty());
  EXPECT_NE(r.errors.front().find("nonexistent-asrt-socket-dir"), std::string::npos)
    << r.errors.front();
  EXPECT_EQ(r.image->GetNumberOfPoints(), 0);
}
