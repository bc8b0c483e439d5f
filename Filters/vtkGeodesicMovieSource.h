/**
 * @class   vtkGeodesicMovieSource
 * @brief   a movie along a path at a quality target, as a temporal image source
 *
 * The movie `asrt movie` makes, frame by frame on request: a scene file, a path (a ramp of the
 * hole's mass, spin or charge from RampFrom to RampTo, or the camera turned about the hole's axis
 * through OrbitDegrees, or through key cameras), NumberOfFrames frames and a QualityTarget in dB.
 * The plan (which frames are keys, traced whole; which are interpolated per pixel between them,
 * with the pixels the target needs re-traced; which are traced because that is cheaper) is made
 * once, in the information pass, from the prior cost estimate and the store, and again only after
 * a setting changed; the first frame requested makes the key frames, coarse first, and the plan
 * learns from each (asrt::planProgressively) and is then final. Frames are made by
 * asrt::MovieMaker (GeodesicMovie.h), the same code as `asrt movie`: the same settings give the
 * same frames.
 *
 * With a StoreConnection, whole frames and re-traced pixels are read from the PostgreSQL store
 * when stored (whoever stored them) and stored when traced. Without one nothing is stored. Either
 * way key frames, once made, and the pixels re-traced for interpolated frames are kept in memory,
 * so that scrubbing back and forth traces nothing twice.
 *
 * Output: a temporal vtkImageData, TIME_STEPS 0, 1, …, NumberOfFrames − 1 (the frame number, as
 * the `.pvd` of `asrt movie`); a requested time is rounded to the nearest frame. Its arrays are
 * vtkGeodesicSource's ("Colors" as scalars, "ObjectId", "ImageOrder", "PathLength",
 * "Termination", "RaysPerPixel"); field data "FrameMethod" (a string: key, traced, interpolated
 * or reused), "EstimatedPsnr" (for a frame traced or read whole, its settings' bound where
 * measured, else infinite), "SettingsPsnr" (asrt::MovieFrameReport::settingsPsnr), "ShareRetraced"
 * (of the frame's pixels traced for it, 1 for a frame traced whole, 0 for one read),
 * "PathParameter" (its value at the frame: mass, spin, charge, orbit angle in degrees or position
 * among the key cameras) and "FrameIndex".
 *
 * Bad settings (no scene file, fewer than 2 frames, a target outside (0, 100] or NaN, an unknown
 * ramp parameter, equal ramp ends, an orbit of 0 or more than 360 degrees, a key-camera file
 * missing or invalid) are errors naming the setting, and the output is empty.
 */
#ifndef vtkGeodesicMovieSource_h
#define vtkGeodesicMovieSource_h

#include "asrtFiltersModule.h" // for export macro
#include "vtkImageAlgorithm.h"

#include <memory> // for std::unique_ptr

class ASRTFILTERS_EXPORT vtkGeodesicMovieSource : public vtkImageAlgorithm
{
public:
  static vtkGeodesicMovieSource* New();
  vtkTypeMacro(vtkGeodesicMovieSource, vtkImageAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  ///@{
  /// The scene, a JSON file; its textures are found beside it.
  vtkSetStringMacro(SceneFileName);
  vtkGetStringMacro(SceneFileName);
  ///@}

  ///@{
  /// The path: "mass", "spin" or "charge" (a ramp from RampFrom to RampTo, frame k at
  /// RampFrom + (RampTo − RampFrom) k / (NumberOfFrames − 1)), "orbit" (the scene's camera
  /// turned about the hole's axis through OrbitDegrees; 360 closes the orbit), or "cameras" (the
  /// camera through the key cameras of CameraKeysFileName, as asrt movie --cameras). Default
  /// "mass".
  vtkSetStringMacro(PathParameter);
  vtkGetStringMacro(PathParameter);
  vtkSetMacro(RampFrom, double);
  vtkGetMacro(RampFrom, double);
  vtkSetMacro(RampTo, double);
  vtkGetMacro(RampTo, double);
  vtkSetMacro(OrbitDegrees, double);
  vtkGetMacro(OrbitDegrees, double);
  vtkSetStringMacro(CameraKeysFileName);
  vtkGetStringMacro(CameraKeysFileName);
  ///@}

  ///@{
  /// Frames of the movie, 2 to 10000 (default 24).
  vtkSetMacro(NumberOfFrames, int);
  vtkGetMacro(NumberOfFrames, int);
  ///@}

  ///@{
  /// The PSNR in dB every interpolated frame is to reach against its converged picture (or,
  /// without HoldToConverged, against the frame traced at its parameters), in (0, 100] (default
  /// 35).
  vtkSetMacro(QualityTarget, double);
  vtkGetMacro(QualityTarget, double);
  ///@}

  ///@{
  /// Whether QualityTarget is against the converged picture (on, the default: the keys' own error
  /// against theirs is measured by a few probe pixels traced converged; asrt::MovieSettings) or
  /// against the frame traced at the frame's parameters.
  vtkSetMacro(HoldToConverged, vtkTypeBool);
  vtkGetMacro(HoldToConverged, vtkTypeBool);
  vtkBooleanMacro(HoldToConverged, vtkTypeBool);
  ///@}

  ///@{
  /// Whether a target the scene's rendering does not reach raises the movie's rendering, as asrt
  /// movie does (on, the default): held to converged, and the scene's rendering the default one,
  /// the first frame requested measures what it reaches on the first and last frames
  /// (MovieMaker::withRenderingForTarget), and below the target plus 1 dB the movie is made at
  /// the adaptive cap asrt::kRaisedRaysPerPixel where that reaches it, else with the accurate
  /// preset. The field RenderingRaised says which.
  vtkSetMacro(RaiseRenderingForTarget, vtkTypeBool);
  vtkGetMacro(RaiseRenderingForTarget, vtkTypeBool);
  vtkBooleanMacro(RaiseRenderingForTarget, vtkTypeBool);
  ///@}

  ///@{
  /// Whether a target the scene's default rendering reaches with room to spare makes the movie at
  /// the cheaper adaptive cap asrt::kLoweredRaysPerPixel, as asrt movie does (on, the default):
  /// where that cap still reaches the target plus 1 dB on the first and last frames (their probes
  /// anti-aliased again at it, MovieMaker::withRenderingForTarget), the frames between are made at
  /// it, the two ends kept as traced. The field RenderingLowered says which.
  vtkSetMacro(LowerRenderingForTarget, vtkTypeBool);
  vtkGetMacro(LowerRenderingForTarget, vtkTypeBool);
  vtkBooleanMacro(LowerRenderingForTarget, vtkTypeBool);
  ///@}

  ///@{
  /// Resolution override (width, height); 0 keeps the scene's.
  vtkSetVector2Macro(Resolution, int);
  vtkGetVector2Macro(Resolution, int);
  ///@}

  ///@{
  /// The PostgreSQL store to read from and accumulate into: a libpq conninfo, or "default" for
  /// the tools' default (the PG* variables, else the private embedded server). Empty (the
  /// default): no store.
  vtkSetStringMacro(StoreConnection);
  vtkGetStringMacro(StoreConnection);
  /// The label of frames stored (default "movie").
  vtkSetStringMacro(StoreLabel);
  vtkGetStringMacro(StoreLabel);
  ///@}

  ///@{
  /// The share of a traced whole frame's rays that may fail numerically or run out of steps before
  /// the frame is refused (default 0.05, as asrt's --max-failed-share); 1 accepts any frame.
  vtkSetClampMacro(MaxFailedShare, double, 0.0, 1.0);
  vtkGetMacro(MaxFailedShare, double);
  ///@}

  /// The plan's frame methods, one a frame (asrt::FrameMethod: 0 reused, 1 key, 2 traced,
  /// 3 interpolated), after the information pass; empty before it or after an error. Until a
  /// frame is requested this is the plan from the prior estimate, then the learnt one.
  int GetNumberOfPlannedKeys();
  int GetPlannedMethod(int frame);

  ///@{
  /// Rays this source traced since its settings last changed (anti-aliasing's extra rays
  /// counted): the cost of what it made, and zero for anything it could reuse.
  vtkGetMacro(RaysTraced, double);
  ///@}

protected:
  vtkGeodesicMovieSource();
  ~vtkGeodesicMovieSource() override;

  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  /// Once per maker: the rendering judged against the target, and raised where it falls short
  /// (RaiseRenderingForTarget) or lowered where a cheaper one reaches it
  /// (LowerRenderingForTarget).
  void JudgeRendering();

  char* SceneFileName = nullptr;
  char* PathParameter = nullptr;
  double RampFrom = 0.1;
  double RampTo = 1.0;
  double OrbitDegrees = 90.0;
  char* CameraKeysFileName = nullptr;
  int NumberOfFrames = 24;
  double QualityTarget = 35.0;
  vtkTypeBool HoldToConverged = 1;
  vtkTypeBool RaiseRenderingForTarget = 1;
  vtkTypeBool LowerRenderingForTarget = 1;
  int Resolution[2] = { 0, 0 };
  char* StoreConnection = nullptr;
  char* StoreLabel = nullptr;
  double MaxFailedShare = 0.05;
  double RaysTraced = 0.0;

private:
  vtkGeodesicMovieSource(const vtkGeodesicMovieSource&) = delete;
  void operator=(const vtkGeodesicMovieSource&) = delete;
  struct Internals;
  std::unique_ptr<Internals> Impl;
};

#endif
