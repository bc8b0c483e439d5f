#include "GeodesicFrameMatching.h"

#include "GeodesicRecordArrays.h"

#include "vtkDataArray.h"
#include "vtkIdList.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"
#include "vtkSmartPointer.h"
#include "vtkStaticPointLocator.h"

namespace asrt
{
namespace
{
class LocatorIndex final : public PointIndex
{
public:
  explicit LocatorIndex(const std::vector<Vec3>& points)
  {
    auto pts = vtkSmartPointer<vtkPoints>::New();
    pts->SetDataTypeToDouble();
    pts->SetNumberOfPoints(static_cast<vtkIdType>(points.size()));
    for (std::size_t k = 0; k < points.size(); ++k)
      pts->SetPoint(static_cast<vtkIdType>(k), points[k].data());
    this->Data->SetPoints(pts);
    this->Locator->SetDataSet(this->Data);
    this->Locator->BuildLocator();
  }

  std::int64_t nearestWithin(const Vec3& x, double radius) const override
  {
    double dist2 = 0;
    return this->Locator->FindClosestPointWithinRadius(radius, x.data(), dist2);
  }

  void within(const Vec3& x, double radius, std::vector<std::int64_t>& out) const override
  {
    // One id list per thread: the queries themselves are thread-safe, the list is not.
    thread_local vtkSmartPointer<vtkIdList> ids = vtkSmartPointer<vtkIdList>::New();
    this->Locator->FindPointsWithinRadius(radius, x.data(), ids);
    out.resize(static_cast<std::size_t>(ids->GetNumberOfIds()));
    for (vtkIdType k = 0; k < ids->GetNumberOfIds(); ++k)
      out[static_cast<std::size_t>(k)] = ids->GetId(k);
  }

private:
  vtkSmartPointer<vtkPolyData> Data = vtkSmartPointer<vtkPolyData>::New();
  vtkSmartPointer<vtkStaticPointLocator> Locator = vtkSmartPointer<vtkStaticPointLocator>::New();
};

vtkDataArray* pointArray(vtkPolyData* hits, const char* name, int components,
                         const std::string& which)
{
  try
  {
    return requirePointArray(hits, name, components);
  }
  catch (const InvalidParameter& e)
  {
    throw InvalidParameter(which + ": the " + e.what());
  }
}
}

PointIndexFactory vtkPointIndexFactory()
{
  return [](const std::vector<Vec3>& points) -> std::unique_ptr<PointIndex>
  { return std::make_unique<LocatorIndex>(points); };
}

FrameSamples frameSamplesFromHits(vtkPolyData* hits, const SceneDescription& scene,
                                  const std::string& which)
{
  if (!hits)
    throw InvalidParameter(which + ": no hit points");
  vtkDataArray* pixel = pointArray(hits, "Pixel", 2, which);
  vtkDataArray* term = pointArray(hits, "Termination", 1, which);
  vtkDataArray* object = pointArray(hits, "ObjectId", 1, which);
  vtkDataArray* uv = pointArray(hits, "UV", 2, which);
  vtkDataArray* length = pointArray(hits, "PathLength", 1, which);
  vtkDataArray* order = pointArray(hits, "ImageOrder", 1, which);
  vtkDataArray* color = pointArray(hits, "Color", 3, which);
  vtkDataArray* jacobian = pointArray(hits, "Jacobian", 4, which);
  return assembleFrame(
    scene.camera.width, scene.camera.height, scene.camera.viewAngle,
    static_cast<std::size_t>(hits->GetNumberOfPoints()),
    [&](std::size_t k, int& i, int& j, PixelSample& s)
    {
      const vtkIdType id = static_cast<vtkIdType>(k);
      i = static_cast<int>(pixel->GetComponent(id, 0));
      j = static_cast<int>(pixel->GetComponent(id, 1));
      const int t = static_cast<int>(term->GetComponent(id, 0));
      if (t < 0 || t > static_cast<int>(Termination::HitObject))
        throw InvalidParameter("unknown termination " + std::to_string(t));
      s.termination = static_cast<Termination>(t);
      hits->GetPoint(id, s.point.data());
      s.objectId = static_cast<std::int32_t>(object->GetComponent(id, 0));
      s.u = uv->GetComponent(id, 0);
      s.v = uv->GetComponent(id, 1);
      s.pathLength = length->GetComponent(id, 0);
      s.imageOrder = static_cast<std::int32_t>(order->GetComponent(id, 0));
      Color c;
      color->GetTuple(id, c.data());
      if (!c.allFinite())
        throw InvalidParameter("its colour is not finite");
      s.rgb = imageColor(c);
      jacobian->GetTuple(id, s.jacobian.data());
    },
    which);
}
}
