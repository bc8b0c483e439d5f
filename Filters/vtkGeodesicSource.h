/**
 * @class   vtkGeodesicSource
 * @brief   traces one light ray per pixel through a scene around a black hole
 *
 * vtkGeodesicSource reads a scene (a JSON file or text: spacetime, camera, objects, integrator and
 * tolerances), traces each pixel's null geodesic backwards from the eye with the scene's
 * integrator, and outputs
 *  - port 0: the rendered frame, a vtkImageData with RGB "Colors" and per-pixel "ObjectId",
 *    "ImageOrder", "PathLength" and "Termination";
 *  - port 1: a vtkPolyData with one vertex per traced ray at its hit point (or where it ended),
 *    carrying every field of the ray's record as point data, and the scene and frame parameters
 *    as field data (without a PixelSubset, the image's "ObjectId", "ImageOrder", "PathLength"
 *    and "Termination" are these points' arrays of the same names, not copies: the points are
 *    the image's pixels in order);
 *  - port 2: optionally, the rays themselves as polylines (point data "Lambda", "R", "AbsH"), for
 *    a chosen subset or stride of pixels; off by default, as a full frame's paths are large.
 *
 * Scene values can be overridden per frame (mass, spin, camera, resolution, method, step), which
 * is how a movie's frames differ. A subset of pixels can be traced alone. VTK pieces split the
 * image by rows. Tracing runs on OpenMP threads; results do not depend on their number. Whole
 * rows are traced a band at a time, each band's records going into the outputs as it is done, so
 * that a large frame's records are never all in memory beside its outputs.
 */
#ifndef vtkGeodesicSource_h
#define vtkGeodesicSource_h

#include "asrtFiltersModule.h" // for export macro
#include "vtkImageAlgorithm.h"
#include "vtkSmartPointer.h" // for members

#include <limits> // for the GridTolerance default
#include <memory> // for std::shared_ptr
#include <string> // for std::string
#include <vector> // for std::vector

namespace asrt
{
struct SceneDescription;
}
class vtkImageData;
class vtkIntArray;
class vtkPolyData;

class ASRTFILTERS_EXPORT vtkGeodesicSource : public vtkImageAlgorithm
{
public:
  static vtkGeodesicSource* New();
  vtkTypeMacro(vtkGeodesicSource, vtkImageAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  ///@{
  /// The scene: a JSON file, or JSON text. Given both, the text is the file's content as the
  /// caller read it (asrt reads files interruptibly): errors name the file, and its textures are
  /// found beside it.
  vtkSetStringMacro(SceneFileName);
  vtkGetStringMacro(SceneFileName);
  vtkSetStringMacro(SceneText);
  vtkGetStringMacro(SceneText);
  ///@}

  ///@{
  /// The directory against which relative texture paths in SceneText are resolved; empty (the
  /// default) means the working directory. (A SceneFileName's own directory is always used for
  /// its textures.) Stored frames keep their scene text as written, so re-tracing one needs this.
  vtkSetStringMacro(TextureDirectory);
  vtkGetStringMacro(TextureDirectory);
  ///@}

  ///@{
  /// Per-frame overrides of the scene. NaN (the default) keeps the scene's value. The scene with
  /// its overrides passes the scene file's checks (asrt::validateScene): a value the file could
  /// not hold is refused with vtkErrorMacro, naming the field ("camera.position: ...").
  vtkSetMacro(Mass, double);
  vtkGetMacro(Mass, double);
  vtkSetMacro(Spin, double);
  vtkGetMacro(Spin, double);
  vtkSetMacro(Charge, double);
  vtkGetMacro(Charge, double);
  vtkSetVector3Macro(CameraPosition, double);
  vtkGetVector3Macro(CameraPosition, double);
  vtkSetVector3Macro(FocalPoint, double);
  vtkGetVector3Macro(FocalPoint, double);
  vtkSetVector3Macro(ViewUp, double);
  vtkGetVector3Macro(ViewUp, double);
  vtkSetMacro(ViewAngle, double);
  vtkGetMacro(ViewAngle, double);
  vtkSetMacro(IntegrationStep, double);
  vtkGetMacro(IntegrationStep, double);
  ///@}

  ///@{
  /// Switches over the overrides above, for front ends whose properties cannot hold NaN
  /// (ParaView's): with OverrideSpacetime off, Mass, Spin and Charge are ignored and the scene's
  /// hole is traced; OverrideCamera covers CameraPosition, FocalPoint, ViewUp and ViewAngle, and
  /// OverrideIntegrationStep covers IntegrationStep. All on by default, so that NaN alone decides.
  vtkSetMacro(OverrideSpacetime, bool);
  vtkGetMacro(OverrideSpacetime, bool);
  vtkBooleanMacro(OverrideSpacetime, bool);
  vtkSetMacro(OverrideCamera, bool);
  vtkGetMacro(OverrideCamera, bool);
  vtkBooleanMacro(OverrideCamera, bool);
  vtkSetMacro(OverrideIntegrationStep, bool);
  vtkGetMacro(OverrideIntegrationStep, bool);
  vtkBooleanMacro(OverrideIntegrationStep, bool);
  ///@}

  ///@{
  /// Resolution override; 0 keeps the scene's.
  vtkSetVector2Macro(Resolution, int);
  vtkGetVector2Macro(Resolution, int);
  ///@}

  ///@{
  /// Integration method override (a name from asrt::methodTable()); empty keeps the scene's.
  vtkSetStringMacro(IntegrationMethod);
  vtkGetStringMacro(IntegrationMethod);
  ///@}

  ///@{
  /// A speed/accuracy preset ("fast", "balanced", "accurate"; asrt::integratorPreset) replacing
  /// the scene's whole integrator; IntegrationMethod and IntegrationStep then refine it, as
  /// fields given beside a preset do in a scene file. Empty (default) keeps the scene's.
  vtkSetStringMacro(IntegrationPreset);
  vtkGetStringMacro(IntegrationPreset);
  ///@}

  ///@{
  /// Anti-aliasing override ("none", "filter" or "adaptive"; asrt::AntialiasOptions), the most
  /// rays an adaptively sampled pixel takes (1 to 1024) and a fixed supersample N × N (1 to 32).
  /// Empty and 0 keep the scene's "rendering" (or the preset's, if IntegrationPreset is set).
  vtkSetStringMacro(Antialias);
  vtkGetStringMacro(Antialias);
  vtkSetMacro(MaxRaysPerPixel, int);
  vtkGetMacro(MaxRaysPerPixel, int);
  vtkSetMacro(Supersample, int);
  vtkGetMacro(Supersample, int);
  ///@}

  ///@{
  /// Adaptive ray grid override (asrt::AntialiasOptions::gridLattice, AdaptiveGrid.h): the step of
  /// the traced lattice (1 traces every pixel, up to 256) and the largest error of the bilinear
  /// (u, v) that leaves a block whole. 0 and NaN keep the scene's "rendering".
  vtkSetMacro(GridLattice, int);
  vtkGetMacro(GridLattice, int);
  vtkSetMacro(GridTolerance, double);
  vtkGetMacro(GridTolerance, double);
  ///@}

  ///@{
  /// Trace only these pixels: a 2-component array of (i, j). Null traces the whole frame.
  /// Untraced pixels of the image are black with Termination 0 ("running"). The frame's scene
  /// (field data "SceneJSON") then names the subset ("subset": count and digest of the pixels),
  /// so that a subset stored in PostgreSQL is a frame of its own, never the whole frame at the
  /// same parameters.
  void SetPixelSubset(vtkIntArray* ij);
  vtkIntArray* GetPixelSubset();
  ///@}

  /// The effective scene text of the frame this source traces with its current settings
  /// (overrides and subset applied): the frame's identity in the store, as the "SceneJSON" field
  /// data will hold it. Nothing is traced. Empty, with an error, if the scene is invalid.
  std::string GetFrameSceneText();
  /// GetFrameSceneText() without reading the scene's textures (their pixels are not part of the
  /// text), so without checking that they can be read: for the frames of a path whose textures
  /// GetFrameSceneText() read once.
  std::string GetFrameSceneTextWithoutImages();

  /// How the traced rays of a frame ended, counted from its image's "Termination" array (port 0
  /// of this source, or the frame vtkGeodesicDistributedSource assembles): counts[0] the rays
  /// traced (pixels left untraced, outside a PixelSubset, are not), counts[1] those ended by a
  /// numerical failure, counts[2] those that used up their step budget. A frame where these two
  /// are more than a few per cent is not a picture of the scene. Returns false, counts zero, if
  /// the image has no Termination array.
  static bool CountRayEnds(vtkImageData* frame, vtkIdType counts[3]);

  ///@{
  /// Output the rays as polylines (port 2), for every PolylineStride-th pixel in i and j, or for
  /// the pixels in PolylinePixels when set.
  vtkSetMacro(GeneratePolylines, bool);
  vtkGetMacro(GeneratePolylines, bool);
  vtkBooleanMacro(GeneratePolylines, bool);
  vtkSetClampMacro(PolylineStride, int, 1, VTK_INT_MAX);
  vtkGetMacro(PolylineStride, int);
  void SetPolylinePixels(vtkIntArray* ij);
  vtkIntArray* GetPolylinePixels();
  /// The same list a pixel at a time (ParaView's repeated properties): ClearPolylinePixels unsets
  /// it, back to the stride; AddPolylinePixel appends (i, j) to a copy, never to an array the
  /// caller set.
  void ClearPolylinePixels();
  void AddPolylinePixel(int i, int j);
  ///@}

  ///@{
  /// Whether the hits output (port 1) holds every record's point and arrays (on, the default).
  /// Off, it holds the frame's field data alone and the image keeps its arrays: for callers that
  /// use the picture only, a 1920x1080 frame's hit points being about 600 MB.
  vtkSetMacro(GenerateHitPoints, bool);
  vtkGetMacro(GenerateHitPoints, bool);
  vtkBooleanMacro(GenerateHitPoints, bool);
  ///@}

  ///@{
  /// Memory the frame may use, in bytes; 0 (default) allows 80 % of this machine's memory. A
  /// resolution that would need more is refused before anything is allocated.
  vtkSetMacro(MemoryLimit, double);
  vtkGetMacro(MemoryLimit, double);
  ///@}

  vtkImageData* GetImageOutput();
  vtkPolyData* GetHitsOutput();
  vtkPolyData* GetPolylinesOutput();

  /// Reads an image file into RGB bytes, bottom row first (the scene's texture loader): PNG with
  /// libpng (asrt::readPngTexture), JPEG with VTK's reader (libjpeg); other formats are refused by
  /// name. The declared size is checked against asrt::TextureLimits before decoding. Throws
  /// asrt::InvalidParameter naming the file if it cannot.
  static void LoadImagePixels(const std::string& path, int& width, int& height,
                              std::vector<unsigned char>& rgb);

protected:
  vtkGeodesicSource();
  ~vtkGeodesicSource() override;

  int FillOutputPortInformation(int port, vtkInformation* info) override;
  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  char* SceneFileName = nullptr;
  char* SceneText = nullptr;
  char* TextureDirectory = nullptr;
  double Mass;
  double Spin;
  double Charge;
  double CameraPosition[3];
  double FocalPoint[3];
  double ViewUp[3];
  double ViewAngle;
  double IntegrationStep;
  bool OverrideSpacetime = true;
  bool OverrideCamera = true;
  bool OverrideIntegrationStep = true;
  int Resolution[2] = { 0, 0 };
  char* IntegrationMethod = nullptr;
  char* IntegrationPreset = nullptr;
  char* Antialias = nullptr;
  int MaxRaysPerPixel = 0;
  int Supersample = 0;
  int GridLattice = 0;
  double GridTolerance = std::numeric_limits<double>::quiet_NaN();
  bool GeneratePolylines = false;
  bool GenerateHitPoints = true;
  int PolylineStride = 10;
  double MemoryLimit = 0.0;
  vtkSmartPointer<vtkIntArray> PixelSubset;
  vtkSmartPointer<vtkIntArray> PolylinePixels;
  // The scene as RequestInformation loaded it (textures decoded once per update).
  std::shared_ptr<asrt::SceneDescription> Cache;
  vtkMTimeType CacheTime = 0;

private:
  vtkGeodesicSource(const vtkGeodesicSource&) = delete;
  void operator=(const vtkGeodesicSource&) = delete;
  struct Internals;
};

#endif
