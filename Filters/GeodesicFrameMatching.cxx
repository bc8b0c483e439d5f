#include "GeodesicFrameMatching.h"

#include "GeodesicRecordArrays.h"

#include "vtkDataArray.h"
#include "vtkPointData.h"
#include "vtkPolyData.h"

namespace asrt
{
namespace
{
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
