/**
 * @class   vtkGeodesicPathInterpolator
 * @brief   movie frames along a path of key frames, interpolated per pixel in the path's parameter
 *
 * Inputs: the hit points of two or more whole frames of one scene (port 1 of vtkGeodesicSource or
 * of vtkGeodesicPostgreSQLReader), in the order of the path, on the repeatable input port 0
 * (AddKeyFrameConnection). They differ along one parameter of the movie: the hole's mass, spin or
 * charge, or the camera's position (an orbit); whatever else differs must follow it smoothly.
 * The path parameter s is the first of mass, spin, charge that differs between the keys, else the
 * eye's angle about the hole, accumulated from key to key; it must change monotonically.
 *
 * Every pixel is predicted from its own records in the nearest 4 key frames, where they end alike
 * (asrt::interpolateAlongPath: cubic in s, falling back to quadratic and linear), re-shaded with
 * the texture filtered over its interpolated footprint. Pixels the keys cannot vouch for (they end
 * otherwise in the keys around t, or beside such a pixel) show the nearer key until re-traced.
 * With a QualityTarget, the filter re-traces them and then, worst estimated first, just enough
 * others for the frame's estimated PSNR against the converged picture at t to reach the target
 * (the estimate's scale is measured by tracing ProbeFraction of the pixels,
 * asrt::completePathFrame; the keys' own error against their converged pictures by a few probe
 * pixels traced converged, asrt::measureSettingsError; the order of re-tracing within each way of
 * predicting weighed by how well the keys predict each other, each inner key predicted from the
 * others, asrt::leaveOneOutError, kept across time steps too). The correspondences between keys
 * that the moved edges match are kept across time steps (asrt::PathMatchCache, the last 3 pairs: at
 * 1920×1080 about 400 MB beside the keys' own records), so that the frames after the first
 * between two keys, or of the next pair, do not match them again.
 *
 * Output: a temporal vtkImageData. TIME_STEPS are k + j/(N + 1) for key k and j = 0 … N (N =
 * NumberOfIntermediateFrames), up to the last key at K − 1: key k is the time k. Any requested
 * time in [0, K − 1] is rendered. The image has the source's arrays ("Colors" as scalars,
 * "ObjectId", "ImageOrder", "PathLength", "Termination", "RaysPerPixel") plus "PathMethod" (0 key,
 * 1 cubic, 2 quadratic, 3 linear, 4 to be re-traced, 5 re-traced, 6 edge blend, 7 moved edge:
 * near an edge the inner keys disagree on, from the keys' scene points moved to t, 8 moved
 * surface: the same, with no edge within a pixel of it at t) and
 * "ErrorEstimate"
 * (the estimated squared colour error, summed over the channels in levels² of 255; infinite where
 * the keys cannot vouch for the pixel, 0 where traced). Field data: "PathParameter" (its value at
 * t), "PathMethodFractions" (the nine methods' shares), "RetracedPixels", "EstimatedPsnr" and
 * "SettingsPsnr" (with a target), and the parameters at t ("Mass", "Spin", "Charge",
 * "CameraPosition", "FocalPoint", "ViewUp"), those of interpolating the two keys around t as
 * vtkGeodesicFrameInterpolator does.
 */
#ifndef vtkGeodesicPathInterpolator_h
#define vtkGeodesicPathInterpolator_h

#include "asrtFiltersModule.h" // for export macro
#include "vtkImageAlgorithm.h"

#include <memory> // for std::unique_ptr

class ASRTFILTERS_EXPORT vtkGeodesicPathInterpolator : public vtkImageAlgorithm
{
public:
  static vtkGeodesicPathInterpolator* New();
  vtkTypeMacro(vtkGeodesicPathInterpolator, vtkImageAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /// The most frames between two keys.
  static constexpr int kMaxIntermediateFrames = 10000;

  ///@{
  /// The key frames, in the order of the path.
  void AddKeyFrameConnection(vtkAlgorithmOutput* output) { this->AddInputConnection(0, output); }
  void RemoveAllKeyFrames() { this->RemoveAllInputConnections(0); }
  ///@}

  ///@{
  /// N, the frames between two neighbouring keys. Default 8; 1 to kMaxIntermediateFrames.
  vtkSetMacro(NumberOfIntermediateFrames, int);
  vtkGetMacro(NumberOfIntermediateFrames, int);
  ///@}

  ///@{
  /// The PSNR in dB that every frame is to reach against the converged picture at its parameters
  /// (or, without HoldToConverged, against the frame traced there with the keys' settings), by
  /// re-tracing; 0 (the default) re-traces nothing (a preview). At most 100.
  vtkSetMacro(QualityTarget, double);
  vtkGetMacro(QualityTarget, double);
  ///@}

  ///@{
  /// Whether QualityTarget is held against the converged picture at t (on, the default) or
  /// against the frame the keys' settings trace at t. On, each inner key's own error against its
  /// converged picture is measured first, by a few probe pixels traced converged
  /// (asrt::measureSettingsError, once per key), and the re-tracing leaves the frame only what
  /// the target allows beyond the inner keys' (their probes pooled).
  vtkSetMacro(HoldToConverged, vtkTypeBool);
  vtkGetMacro(HoldToConverged, vtkTypeBool);
  vtkBooleanMacro(HoldToConverged, vtkTypeBool);
  ///@}

  ///@{
  /// With HoldToConverged: whether a target above what the key frames' settings reach around t
  /// is met by tracing the pixels that hold their error (the sampled edges first, by the keys'
  /// probes) with the converged rendering (on, the default; asrt::SettingsRefinement), or the
  /// frame held to within about 1 dB of the keys' own bound (off, with a warning).
  vtkSetMacro(RaiseRenderingForTarget, vtkTypeBool);
  vtkGetMacro(RaiseRenderingForTarget, vtkTypeBool);
  vtkBooleanMacro(RaiseRenderingForTarget, vtkTypeBool);
  ///@}

  ///@{
  /// The share of a frame's pixels traced to measure the estimate's scale (default 0.01, at least
  /// 64 pixels), in (0, 1].
  vtkSetMacro(ProbeFraction, double);
  vtkGetMacro(ProbeFraction, double);
  ///@}

  ///@{
  /// Where relative texture paths of the frames' scene lie (stored scenes keep paths as written,
  /// relative to their scene file); empty: the working directory.
  vtkSetStringMacro(TextureDirectory);
  vtkGetStringMacro(TextureDirectory);
  ///@}

  /// The path parameter the keys vary in: "mass", "spin", "charge" or "orbit angle" (degrees);
  /// empty before the first update.
  const char* GetPathParameterName() const;

  ///@{
  /// What the last RequestData did: pixels re-traced (probes included), pixels the keys could not
  /// vouch for, the estimated PSNR (0 without a target), and the bound on the inner keys'
  /// own PSNR against their converged pictures (infinite without HoldToConverged or a target);
  /// the pixels traced with the converged rendering (RaiseRenderingForTarget).
  vtkGetMacro(LastRetracedCount, vtkIdType);
  vtkGetMacro(LastConvergedCount, vtkIdType);
  vtkGetMacro(LastMustRetraceCount, vtkIdType);
  vtkGetMacro(LastEstimatedPsnr, double);
  vtkGetMacro(LastSettingsPsnr, double);
  ///@}

protected:
  vtkGeodesicPathInterpolator();
  ~vtkGeodesicPathInterpolator() override;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestUpdateExtent(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  int NumberOfIntermediateFrames = 8;
  double QualityTarget = 0.0;
  vtkTypeBool HoldToConverged = 1;
  vtkTypeBool RaiseRenderingForTarget = 1;
  double ProbeFraction = 0.01;
  char* TextureDirectory = nullptr;
  vtkIdType LastRetracedCount = 0;
  vtkIdType LastConvergedCount = 0;
  vtkIdType LastMustRetraceCount = 0;
  double LastEstimatedPsnr = 0.0;
  double LastSettingsPsnr = 0.0;

private:
  vtkGeodesicPathInterpolator(const vtkGeodesicPathInterpolator&) = delete;
  void operator=(const vtkGeodesicPathInterpolator&) = delete;
  struct Internals;
  std::unique_ptr<Internals> Impl;
};

#endif
