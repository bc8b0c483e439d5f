// vtkGeodesicSource on a frame of several bands (it traces whole rows a band at a time and never
// holds all the records): its ports against the records of FrameTracer::traceRows over the whole
// frame, field by field and bit for bit, with the arrays' types, and the image against the same
// records pixel by pixel.
#include "FiltersTestUtilities.h"
#include "FrameTracer.h"
#include "RowBands.h"
#include "SceneFile.h"

#include "vtkCellArray.h"
#include "vtkPoints.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

using asrt::testing::bitsOf;
using asrt::testing::MessageCatcher;
using asrt::testing::RecordBits;

namespace
{
// Wide enough that the default band is a few rows, and a row more than one band high.
constexpr int kW = 512;
constexpr int kH = static_cast<int>(asrt::kBandPixels / kW) + 3;

/// Fig. 1's cylinders and floor without image textures, at the fast preset.
std::string sceneText()
{
  return R"({
  "spacetime": {"mass": 1},
  "camera": {"position": [0, -30, 8], "focalPoint": [0, 0, 0], "viewUp": [0, 0, 1],
             "viewAngle": 30, "resolution": [)" +
         std::to_string(kW) + ", " + std::to_string(kH) + R"(]},
  "integrator": {"preset": "fast"},
  "objects": [
    {"type": "celestialSphere", "id": 0, "radius": 500, "texture": {"color": [0.1, 0.1, 0.3]}},
    {"type": "cylinder", "id": 1, "base": [-15, 0, 0], "axis": [1, 0, 0], "radius": 0.5,
     "height": 30, "texture": {"checker": [8, 30]}},
    {"type": "cylinder", "id": 2, "base": [0, -15, 0], "axis": [0, 1, 0], "radius": 0.5,
     "height": 30, "texture": {"checker": [8, 30]}},
    {"type": "rectangle", "id": 4, "center": [0, 5, -10], "uAxis": [1, 0, 0],
     "vAxis": [0, 1, 0], "halfWidth": 20, "halfHeight": 20, "texture": {"checker": [10, 10]}}
  ]})";
}

/// A record as recordsByPixel lays out a hit point: the point, then every record array's
/// components, each as the bits of its value as a double.
RecordBits bitsOfRecord(const asrt::RayRecord& r)
{
  RecordBits b;
  auto add = [&b](std::initializer_list<double> values)
  {
    for (double v : values)
      b.push_back(bitsOf(v));
  };
  auto add3 = [&add](const asrt::Vec3& v) { add({ v.x(), v.y(), v.z() }); };
  add3(r.hitPoint);
  add({ double(r.i), double(r.j) });
  add3(r.origin);
  add3(r.direction);
  add({ r.momentum[0], r.momentum[1], r.momentum[2], r.momentum[3] });
  add({ double(static_cast<int>(r.termination)), double(r.objectId) });
  add3(r.hitNormal);
  add({ r.u, r.v, r.chordError, r.affineLength, r.winding, double(r.imageOrder), double(r.steps),
        r.maxAbsH });
  add3(r.color);
  add({ static_cast<double>(r.raysPerPixel) });
  add({ r.dudi, r.dudj, r.dvdi, r.dvdj });
  add({ r.traced ? 1.0 : 0.0 });
  return b;
}
}

TEST(GeodesicSourceBands, PortsHoldTheRecordsOfTheWholeFrameTracedTogether)
{
  ASSERT_GT(kW * kH, static_cast<int>(asrt::kBandPixels)) << "the frame must span two bands";
  const std::string text = sceneText();
  vtkNew<vtkGeodesicSource> source;
  vtkNew<MessageCatcher> catcher;
  asrt::testing::watch(source, catcher);
  source->SetSceneText(text.c_str());
  source->Update();
  ASSERT_TRUE(catcher->Errors.empty()) << catcher->AllErrors();

  const std::vector<asrt::RayRecord> truth =
    asrt::FrameTracer(asrt::parseScene(text, "", nullptr)).traceRows(0, kH);
  ASSERT_EQ(truth.size(), static_cast<size_t>(kW) * kH);

  // Port 1: a vertex a ray, in the tracer's order, every field as it traced it.
  vtkPolyData* hits = source->GetHitsOutput();
  ASSERT_EQ(hits->GetNumberOfPoints(), kW * kH);
  ASSERT_EQ(hits->GetNumberOfVerts(), kW * kH);
  EXPECT_EQ(hits->GetPoints()->GetDataType(), VTK_DOUBLE);
  const std::vector<std::pair<const char*, int>> types = {
    { "Pixel", VTK_INT },         { "Origin", VTK_DOUBLE },   { "Direction", VTK_DOUBLE },
    { "Momentum", VTK_DOUBLE },   { "Termination", VTK_INT }, { "ObjectId", VTK_INT },
    { "HitNormal", VTK_DOUBLE },  { "UV", VTK_DOUBLE },       { "ChordError", VTK_DOUBLE },
    { "PathLength", VTK_DOUBLE }, { "Winding", VTK_DOUBLE },  { "ImageOrder", VTK_INT },
    { "Steps", VTK_LONG_LONG },   { "MaxAbsH", VTK_DOUBLE },  { "Color", VTK_DOUBLE },
    { "RaysPerPixel", VTK_INT },  { "Jacobian", VTK_DOUBLE }, { "Traced", VTK_UNSIGNED_CHAR }
  };
  for (const auto& [name, type] : types)
  {
    vtkDataArray* a = hits->GetPointData()->GetArray(name);
    ASSERT_NE(a, nullptr) << name;
    EXPECT_EQ(a->GetDataType(), type) << name;
  }
  const auto records = asrt::testing::recordsByPixel(hits);
  ASSERT_EQ(records.size(), truth.size());
  vtkDataArray* pixel = hits->GetPointData()->GetArray("Pixel");
  int differing = 0, jacobians = 0;
  for (size_t k = 0; k < truth.size(); ++k)
  {
    const asrt::RayRecord& r = truth[k];
    ASSERT_EQ(pixel->GetComponent(static_cast<vtkIdType>(k), 0), r.i) << "point " << k;
    ASSERT_EQ(pixel->GetComponent(static_cast<vtkIdType>(k), 1), r.j) << "point " << k;
    const RecordBits& got = records.at({ r.i, r.j });
    if (got != bitsOfRecord(r) && ++differing <= 5)
      ADD_FAILURE() << "pixel (" << r.i << ", " << r.j
                    << "): " << asrt::testing::describeDifference(got, bitsOfRecord(r));
    jacobians += !std::isnan(r.dudj);
  }
  EXPECT_EQ(differing, 0);
  EXPECT_GT(jacobians, kW) << "too few vertical Jacobians to tell the bands' seams";
  vtkIdType n = 0;
  const vtkIdType* ids = nullptr;
  for (vtkIdType c = 0; c < kW * kH; c += 997)
  {
    hits->GetVerts()->GetCellAtId(c, n, ids);
    ASSERT_EQ(n, 1);
    EXPECT_EQ(ids[0], c);
  }

  // Port 0: the picture and the per-pixel arrays of the same records.
  vtkImageData* image = source->GetImageOutput();
  ASSERT_EQ(image->GetNumberOfPoints(), kW * kH);
  vtkPointData* pd = image->GetPointData();
  vtkDataArray* colors = pd->GetScalars();
  ASSERT_NE(colors, nullptr);
  EXPECT_STREQ(colors->GetName(), "Colors");
  EXPECT_EQ(colors->GetDataType(), VTK_UNSIGNED_CHAR);
  const std::vector<std::pair<const char*, int>> imageTypes = { { "ObjectId", VTK_INT },
                                                                { "ImageOrder", VTK_INT },
                                                                { "PathLength", VTK_DOUBLE },
                                                                { "Termination", VTK_INT } };
  for (const auto& [name, type] : imageTypes)
  {
    ASSERT_NE(pd->GetArray(name), nullptr) << name;
    EXPECT_EQ(pd->GetArray(name)->GetDataType(), type) << name;
  }
  int mismatches = 0;
  for (const asrt::RayRecord& r : truth)
  {
    int ijk[3] = { r.i, r.j, 0 };
    const vtkIdType p = image->ComputePointId(ijk);
    bool same = pd->GetArray("ObjectId")->GetComponent(p, 0) == r.objectId &&
                pd->GetArray("ImageOrder")->GetComponent(p, 0) == r.imageOrder &&
                bitsOf(pd->GetArray("PathLength")->GetComponent(p, 0)) == bitsOf(r.affineLength) &&
                pd->GetArray("Termination")->GetComponent(p, 0) == static_cast<int>(r.termination);
    for (int c = 0; c < 3; ++c)
      same =
        same && colors->GetComponent(p, c) == std::lround(255.0 * std::clamp(r.color[c], 0.0, 1.0));
    mismatches += !same;
  }
  EXPECT_EQ(mismatches, 0) << "pixels of the image unlike the tracer's records";
}
