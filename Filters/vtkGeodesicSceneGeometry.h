/**
 * @class   vtkGeodesicSceneGeometry
 * @brief   the objects of an ASRT scene as coloured polygonal surfaces, with the horizon
 *
 * Reads the same scene as vtkGeodesicSource and tessellates every object over its own surface
 * coordinates (u, v), coloured by its texture ("Colors", RGB point data; "ObjectId" cell data).
 * The hole's outer horizon is added as a black surface (an oblate spheroid for Kerr, in the
 * Kerr–Schild chart), so that 3D views of ray bundles show what the rays fall into. Infinite
 * planes are drawn over PlaneExtent M around their centre; the celestial sphere is optional.
 */
#ifndef vtkGeodesicSceneGeometry_h
#define vtkGeodesicSceneGeometry_h

#include "asrtFiltersModule.h" // for export macro
#include "vtkPolyDataAlgorithm.h"

class ASRTFILTERS_EXPORT vtkGeodesicSceneGeometry : public vtkPolyDataAlgorithm
{
public:
  static vtkGeodesicSceneGeometry* New();
  vtkTypeMacro(vtkGeodesicSceneGeometry, vtkPolyDataAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  ///@{
  /// The scene, as for vtkGeodesicSource (text wins over file); Mass and Spin override it.
  vtkSetStringMacro(SceneFileName);
  vtkGetStringMacro(SceneFileName);
  vtkSetStringMacro(SceneText);
  vtkGetStringMacro(SceneText);
  vtkSetMacro(Mass, double);
  vtkGetMacro(Mass, double);
  vtkSetMacro(Spin, double);
  vtkGetMacro(Spin, double);
  /// Off: Mass and Spin are ignored, the scene's hole is drawn (for front ends whose properties
  /// cannot hold NaN, as vtkGeodesicSource's OverrideSpacetime). On by default.
  vtkSetMacro(OverrideSpacetime, bool);
  vtkGetMacro(OverrideSpacetime, bool);
  vtkBooleanMacro(OverrideSpacetime, bool);
  ///@}

  ///@{
  /// Samples per unit of u and v on each object (at least 2).
  vtkSetClampMacro(Resolution, int, 2, 4096);
  vtkGetMacro(Resolution, int);
  ///@}

  ///@{
  vtkSetMacro(IncludeCelestialSphere, bool);
  vtkGetMacro(IncludeCelestialSphere, bool);
  vtkBooleanMacro(IncludeCelestialSphere, bool);
  vtkSetMacro(IncludeHorizon, bool);
  vtkGetMacro(IncludeHorizon, bool);
  vtkBooleanMacro(IncludeHorizon, bool);
  /// Half-size, in M, over which infinite planes are drawn.
  vtkSetMacro(PlaneExtent, double);
  vtkGetMacro(PlaneExtent, double);
  ///@}

protected:
  vtkGeodesicSceneGeometry();
  ~vtkGeodesicSceneGeometry() override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  char* SceneFileName = nullptr;
  char* SceneText = nullptr;
  double Mass;
  double Spin;
  bool OverrideSpacetime = true;
  int Resolution = 64;
  bool IncludeCelestialSphere = false;
  bool IncludeHorizon = true;
  double PlaneExtent = 40.0;

private:
  vtkGeodesicSceneGeometry(const vtkGeodesicSceneGeometry&) = delete;
  void operator=(const vtkGeodesicSceneGeometry&) = delete;
};

#endif
