// The bound on polylines: the rays drawn as polylines are counted before anything is traced, for a
// stride and for an explicit pixel list, and refused beyond 100000 with the count named.
#include "FiltersTestUtilities.h"

using asrt::testing::MessageCatcher;

namespace
{
/// The first error of a frame of the flat scene at w × h with polylines.
std::string polylineError(int w, int h, int stride, vtkIntArray* pixels = nullptr)
{
  vtkNew<vtkGeodesicSource> source;
  vtkNew<MessageCatcher> catcher;
  asrt::testing::watch(source, catcher);
  source->SetSceneFileName(asrt::testing::scenePath("fig2-no-hole.json").c_str());
  source->SetResolution(w, h);
  source->GeneratePolylinesOn();
  source->SetPolylineStride(stride);
  source->SetPolylinePixels(pixels);
  source->Update();
  return catcher->Errors.empty() ? std::string("(no error)") : catcher->Errors.front();
}
}

TEST(PolylineBound, StrideCountIsRefusedBeyondTheCap)
{
  // 317 x 1000 at stride 1; 334 x 334 at stride 3 on 1000 x 1000 (columns and rows rounded up).
  EXPECT_NE(polylineError(317, 1000, 1).find("317000 rays asked for as polylines; at most 100000"),
            std::string::npos);
  EXPECT_NE(polylineError(1000, 1000, 3).find("111556 rays asked for as polylines"),
            std::string::npos);
}

TEST(PolylineBound, PixelListIsRefusedBeyondTheCap)
{
  std::vector<std::pair<int, int>> ij(100001, { 1, 1 });
  EXPECT_NE(polylineError(4, 4, 1, asrt::testing::pixelList(ij)).find("100001 rays asked for"),
            std::string::npos);
}

TEST(PolylineBound, SmallRequestsAreDrawn)
{
  EXPECT_EQ(polylineError(12, 8, 4), "(no error)");
}
