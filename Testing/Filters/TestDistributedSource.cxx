// vtkGeodesicDistributedSource on one process (no controller, or a one-process controller): it
// is vtkGeodesicSource's frame, and it refuses what only the single source does. The split and
// the exchange are tested in Testing/Parallel, the MPI runs under mpirun there too.
#include "FiltersTestUtilities.h"
#include "vtkGeodesicDistributedSource.h"
#include "vtkGeodesicSource.h"

#include "vtkDoubleArray.h"
#include "vtkDummyController.h"

#include <gtest/gtest.h>

#include <cstring>

using asrt::testing::scenePath;

namespace
{
constexpr int kW = 37;
constexpr int kH = 29;
}

namespace
{
/// Every point array of two images, bit for bit.
void expectSameImage(vtkImageData* a, vtkImageData* b)
{
  int ea[6], eb[6];
  a->GetExtent(ea);
  b->GetExtent(eb);
  ASSERT_TRUE(std::equal(ea, ea + 6, eb));
  ASSERT_EQ(a->GetPointData()->GetNumberOfArrays(), b->GetPointData()->GetNumberOfArrays());
  for (int k = 0; k < a->GetPointData()->GetNumberOfArrays(); ++k)
  {
    vtkDataArray* x = a->GetPointData()->GetArray(k);
    vtkDataArray* y = b->GetPointData()->GetArray(x->GetName());
    ASSERT_NE(y, nullptr) << x->GetName();
    ASSERT_EQ(x->GetDataType(), y->GetDataType()) << x->GetName();
    ASSERT_EQ(x->GetNumberOfValues(), y->GetNumberOfValues());
    EXPECT_EQ(std::memcmp(x->GetVoidPointer(0), y->GetVoidPointer(0),
                          x->GetNumberOfValues() * x->GetDataTypeSize()),
              0)
      << x->GetName();
  }
}
}

TEST(GeodesicDistributedSource, AloneItGivesTheSourcesFrame)
{
  vtkNew<vtkGeodesicSource> single;
  single->SetSceneFileName(scenePath("kerr-disk.json").c_str());
  single->SetResolution(kW, kH);
  single->Update();

  for (bool dummy : { false, true })
  {
    SCOPED_TRACE(dummy ? "one-process controller" : "no controller");
    vtkNew<vtkDummyController> controller;
    vtkNew<vtkGeodesicDistributedSource> s;
    vtkNew<asrt::testing::MessageCatcher> catcher;
    asrt::testing::watch(s, catcher);
    s->SetController(dummy ? controller.Get() : nullptr);
    s->SetSceneFileName(scenePath("kerr-disk.json").c_str());
    s->SetResolution(kW, kH);
    s->Update();
    ASSERT_TRUE(catcher->Errors.empty()) << catcher->AllErrors();
    expectSameImage(s->GetImageOutput(), single->GetImageOutput());
    EXPECT_EQ(asrt::testing::recordsByPixel(s->GetHitsOutput()),
              asrt::testing::recordsByPixel(single->GetHitsOutput()));
    vtkDoubleArray* work = s->GetRankWork();
    ASSERT_EQ(work->GetNumberOfTuples(), 1);
    vtkDataArray* steps = single->GetHitsOutput()->GetPointData()->GetArray("Steps");
    double total = 0;
    for (vtkIdType k = 0; k < steps->GetNumberOfTuples(); ++k)
      total += steps->GetComponent(k, 0);
    EXPECT_EQ(work->GetComponent(0, 0), total);
    EXPECT_EQ(work->GetComponent(0, 1), static_cast<double>(kW * kH));
    EXPECT_EQ(s->GetFrameId(), -1); // nothing stored unless asked
  }
}

TEST(GeodesicDistributedSource, RefusesWhatOnlyTheSingleSourceDoes)
{
  for (int what = 0; what < 2; ++what)
  {
    vtkNew<vtkGeodesicDistributedSource> s;
    vtkNew<asrt::testing::MessageCatcher> catcher;
    asrt::testing::watch(s, catcher);
    s->SetController(nullptr);
    s->SetSceneFileName(scenePath("kerr-disk.json").c_str());
    s->SetResolution(8, 8);
    if (what == 0)
      s->SetPixelSubset(asrt::testing::pixelList({ { 1, 1 } }));
    else
      s->GeneratePolylinesOn();
    s->Update();
    EXPECT_TRUE(catcher->Mentions(what == 0 ? "PixelSubset" : "GeneratePolylines"))
      << catcher->AllErrors();
    EXPECT_EQ(s->GetImageOutput()->GetNumberOfPoints(), 0);
  }
}

TEST(GeodesicDistributedSource, ASceneErrorIsReportedOnce)
{
  vtkNew<vtkGeodesicDistributedSource> s;
  vtkNew<asrt::testing::MessageCatcher> catcher;
  asrt::testing::watch(s, catcher);
  s->SetController(nullptr);
  s->SetSceneFileName(scenePath("kerr-disk.json").c_str());
  s->SetSpin(1.5);
  s->Update();
  ASSERT_FALSE(catcher->Errors.empty());
  EXPECT_TRUE(catcher->Mentions("exceeds the mass")) << catcher->AllErrors();
}
