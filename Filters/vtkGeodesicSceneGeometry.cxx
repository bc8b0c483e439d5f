#include "vtkGeodesicSceneGeometry.h"

#include "GeodesicSceneLoading.h"

#include "vtkCellArray.h"
#include "vtkCellData.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkIntArray.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkPolyData.h"
#include "vtkUnsignedCharArray.h"

#include <algorithm>
#include <cmath>
#include <limits>

vtkStandardNewMacro(vtkGeodesicSceneGeometry);

vtkGeodesicSceneGeometry::vtkGeodesicSceneGeometry()
  : Mass(std::numeric_limits<double>::quiet_NaN())
  , Spin(std::numeric_limits<double>::quiet_NaN())
{
  this->SetNumberOfInputPorts(0);
}

vtkGeodesicSceneGeometry::~vtkGeodesicSceneGeometry()
{
  this->SetSceneFileName(nullptr);
  this->SetSceneText(nullptr);
}

namespace
{
/// Appends an (nu + 1) × (nv + 1) grid of quads of surface(u, v) over [u0, u1] × [v0, v1].
template<class Surface, class Shade>
void appendGrid(vtkPoints* points, vtkCellArray* quads, vtkUnsignedCharArray* colors,
                vtkIntArray* ids, int id, int nu, int nv, double u0, double u1, double v0,
                double v1, const Surface& surface, const Shade& shade)
{
  const vtkIdType first = points->GetNumberOfPoints();
  for (int b = 0; b <= nv; ++b)
    for (int a = 0; a <= nu; ++a)
    {
      const double u = u0 + (u1 - u0) * a / nu, v = v0 + (v1 - v0) * b / nv;
      const asrt::Vec3 x = surface(u, v);
      points->InsertNextPoint(x.data());
      const asrt::Color c = shade(u, v);
      const unsigned char rgb[3] = {
        static_cast<unsigned char>(std::lround(255 * std::clamp(c[0], 0.0, 1.0))),
        static_cast<unsigned char>(std::lround(255 * std::clamp(c[1], 0.0, 1.0))),
        static_cast<unsigned char>(std::lround(255 * std::clamp(c[2], 0.0, 1.0)))
      };
      colors->InsertNextTypedTuple(rgb);
    }
  for (int b = 0; b < nv; ++b)
    for (int a = 0; a < nu; ++a)
    {
      const vtkIdType p0 = first + static_cast<vtkIdType>(b) * (nu + 1) + a;
      const vtkIdType quad[4] = { p0, p0 + 1, p0 + nu + 2, p0 + nu + 1 };
      quads->InsertNextCell(4, quad);
      ids->InsertNextValue(id);
    }
}
}

int vtkGeodesicSceneGeometry::RequestData(vtkInformation*, vtkInformationVector**,
                                          vtkInformationVector* outputVector)
{
  vtkPolyData* output = vtkPolyData::GetData(outputVector, 0);
  try
  {
    asrt::SceneDescription d = asrt::loadScene(this->SceneText, this->SceneFileName);
    if (this->OverrideSpacetime && !std::isnan(this->Mass))
      d.spacetime.mass = this->Mass;
    if (this->OverrideSpacetime && !std::isnan(this->Spin))
      d.spacetime.spin = this->Spin;
    const auto st = asrt::makeSpacetime(d.spacetime);

    vtkNew<vtkPoints> points;
    points->SetDataTypeToDouble();
    vtkNew<vtkCellArray> quads;
    vtkNew<vtkUnsignedCharArray> colors;
    colors->SetName("Colors");
    colors->SetNumberOfComponents(3);
    vtkNew<vtkIntArray> ids;
    ids->SetName("ObjectId");
    const int n = this->Resolution;
    for (const auto& object : d.scene->objects())
    {
      const std::string type = object->type();
      if (type == "celestialSphere" && !this->IncludeCelestialSphere)
        continue;
      const asrt::SceneObject& o = *object;
      auto surface = [&o](double u, double v) { return o.surfacePoint(u, v); };
      // Closed surfaces wrap u and clamp v, as the textures do; infinite planes repeat in both.
      const bool tiled = o.isInfinite();
      auto shade = [&o, tiled](double u, double v)
      {
        return o.texture().sample(u - std::floor(u),
                                  tiled ? v - std::floor(v) : std::clamp(v, 0.0, 1.0));
      };
      if (o.isInfinite())
      {
        // One texture tile spans |∂x/∂u|; draw PlaneExtent M around the centre.
        const double tile = (o.surfacePoint(1.0, 0.5) - o.surfacePoint(0.0, 0.5)).norm();
        const double span = this->PlaneExtent / tile;
        const int cells = std::max(2, static_cast<int>(2 * span * 8));
        appendGrid(points, quads, colors, ids, o.id(), cells, cells, 0.5 - span, 0.5 + span,
                   0.5 - span, 0.5 + span, surface, shade);
      }
      else
      {
        appendGrid(points, quads, colors, ids, o.id(), n, n, 0.0, 1.0, 0.0, 1.0, surface, shade);
      }
    }
    const double rPlus = st->outerHorizon();
    if (this->IncludeHorizon && rPlus > 0.0)
    {
      // The horizon r = r₊ in the Kerr–Schild chart: x² + y² = (r₊² + a²) sin²θ, z = r₊ cos θ.
      const double a = st->spin(), rho = std::sqrt(rPlus * rPlus + a * a);
      auto horizon = [rho, rPlus](double u, double v)
      {
        const double phi = 2.0 * M_PI * u, theta = M_PI * v;
        return asrt::Vec3(rho * std::sin(theta) * std::cos(phi),
                          rho * std::sin(theta) * std::sin(phi), rPlus * std::cos(theta));
      };
      appendGrid(points, quads, colors, ids, -1, n, n / 2 + 1, 0.0, 1.0, 0.0, 1.0, horizon,
                 [](double, double) { return asrt::Color(0, 0, 0); });
    }
    output->SetPoints(points);
    output->SetPolys(quads);
    output->GetPointData()->SetScalars(colors);
    output->GetCellData()->AddArray(ids);
  }
  catch (const std::exception& e)
  {
    vtkErrorMacro(<< e.what());
    output->Initialize();
    return 0;
  }
  return 1;
}

void vtkGeodesicSceneGeometry::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "SceneFileName: " << (this->SceneFileName ? this->SceneFileName : "(none)")
     << "\n";
  os << indent << "SceneText: " << (this->SceneText ? "(set)" : "(none)") << "\n";
  os << indent << "OverrideSpacetime: " << this->OverrideSpacetime << "\n";
  os << indent << "Mass: " << this->Mass << "\n";
  os << indent << "Spin: " << this->Spin << "\n";
  os << indent << "Resolution: " << this->Resolution << "\n";
  os << indent << "IncludeCelestialSphere: " << this->IncludeCelestialSphere << "\n";
  os << indent << "IncludeHorizon: " << this->IncludeHorizon << "\n";
  os << indent << "PlaneExtent: " << this->PlaneExtent << "\n";
}
