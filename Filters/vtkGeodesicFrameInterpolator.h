/**
 * @class   vtkGeodesicFrameInterpolator
 * @brief   movie frames between two traced frames, by matching their rays (no re-tracing)
 *
 * Inputs: the hit points of two whole frames of one scene (port 1 of vtkGeodesicSource or of
 * vtkGeodesicPostgreSQLReader), A on input port 0 and B on input port 1. They may differ in the
 * hole's mass, spin and charge and in the camera's position, focal point and view-up (and in the
 * integration method); everything else must be equal.
 *
 * Output: a temporal vtkImageData. RequestInformation declares TIME_STEPS t_k = k/(N + 1),
 * k = 0 … N + 1 (N = NumberOfIntermediateFrames; t = 0 is A, t = 1 is B) and TIME_RANGE [0, 1];
 * any requested time in [0, 1] is rendered as such (the interpolation is continuous in t), times
 * outside are clamped. The image has the source's arrays ("Colors" RGB as scalars, "ObjectId",
 * "ImageOrder", "PathLength", "Termination", taken from the ray in front at each pixel) plus
 * "InterpolationClass" (0 matched, 1 one-sided, 2 hole-filled, 3 ambiguous, 4 re-traced) and, in
 * exact mode, "Disagreement" (the largest channel difference between what A's splats alone and
 * B's splats alone show at the pixel, 255 where only one of them reaches it). Field data:
 * "InterpolationTime", "InterpolationFractions" (the five classes' shares of the pixels),
 * "HolePixels", "RetracedPixels", and the parameters at t ("Mass", "Spin", "Charge",
 * "CameraPosition", "FocalPoint", "ViewUp").
 *
 * The parameters at t: mass, spin and charge linear, focal point linear, view-up
 * normalised-linear, the eye along CameraPath (default: an orbit about the hole — radius linear,
 * direction on the great circle — when either frame has M > 0, a straight line in flat space).
 *
 * The correspondence (asrt::matchFrames, with vtkStaticPointLocator) is computed once per pair
 * of inputs and kept across time requests until an input changes; each frame is then splatted
 * (asrt::renderFrame). ExactMode re-traces the pixels that are holes, ambiguous, or on which A and
 * B disagree by more than RetraceDisagreement, at the parameters of t, with an internal
 * vtkGeodesicSource in its pixel-subset mode, and composites them in. With StoreRetracedRays,
 * those rays are accumulated in PostgreSQL as a subset frame of their own (its scene names the
 * subset, so it never collides with a whole frame at the same parameters); a later request for
 * the same pixels at the same parameters reads them back instead of tracing them again.
 */
#ifndef vtkGeodesicFrameInterpolator_h
#define vtkGeodesicFrameInterpolator_h

#include "asrtFiltersModule.h" // for export macro
#include "vtkImageAlgorithm.h"

#include <memory> // for std::unique_ptr

class ASRTFILTERS_EXPORT vtkGeodesicFrameInterpolator : public vtkImageAlgorithm
{
public:
  static vtkGeodesicFrameInterpolator* New();
  vtkTypeMacro(vtkGeodesicFrameInterpolator, vtkImageAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /// The most intermediate frames a pair may be cut into: beyond that, neighbouring frames lie
  /// closer than 10⁻⁴ in t, far finer than anything the matching resolves (trace more key frames
  /// instead). More is an error, as is none.
  static constexpr int kMaxIntermediateFrames = 10000;

  ///@{
  /// Frame A (t = 0) and frame B (t = 1): hit points of whole frames.
  void SetFrameAConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(0, output); }
  void SetFrameBConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(1, output); }
  ///@}

  ///@{
  /// N, the frames between A and B: TIME_STEPS holds N + 2 times. Default 8; 1 to
  /// kMaxIntermediateFrames.
  vtkSetMacro(NumberOfIntermediateFrames, int);
  vtkGetMacro(NumberOfIntermediateFrames, int);
  ///@}

  enum CameraPathType
  {
    AUTOMATIC = 0,
    LINEAR = 1,
    ORBIT = 2
  };
  ///@{
  /// How the eye moves from A to B (see the class description). Default AUTOMATIC.
  vtkSetClampMacro(CameraPath, int, AUTOMATIC, ORBIT);
  vtkGetMacro(CameraPath, int);
  void SetCameraPathToAutomatic() { this->SetCameraPath(AUTOMATIC); }
  void SetCameraPathToLinear() { this->SetCameraPath(LINEAR); }
  void SetCameraPathToOrbit() { this->SetCameraPath(ORBIT); }
  ///@}

  ///@{
  /// Matching: a point matches a ray of the other frame that hit within this many pixel
  /// footprints of it (default 1.5).
  vtkSetMacro(MatchTolerance, double);
  vtkGetMacro(MatchTolerance, double);
  ///@}

  ///@{
  /// Splatting: the largest magnification a splat's footprint follows (default 4; beyond it the
  /// gaps are filled as holes), and the relative path-length margin within which surfaces blend
  /// (default 0.02).
  vtkSetMacro(MaxMagnification, double);
  vtkGetMacro(MaxMagnification, double);
  vtkSetMacro(DepthTolerance, double);
  vtkGetMacro(DepthTolerance, double);
  ///@}

  ///@{
  /// Re-trace the pixels that interpolation cannot vouch for (holes, ambiguous ones, and those on
  /// which A's and B's estimates differ by more than RetraceDisagreement levels of 255 in some
  /// channel; default 64, 255 re-traces holes and ambiguous pixels only). Off by default. The
  /// ends (t = 0, 1) are the traced frames and are never re-traced.
  vtkSetMacro(ExactMode, bool);
  vtkGetMacro(ExactMode, bool);
  vtkBooleanMacro(ExactMode, bool);
  vtkSetClampMacro(RetraceDisagreement, int, 0, 255);
  vtkGetMacro(RetraceDisagreement, int);
  ///@}

  ///@{
  /// Where relative texture paths of the frames' scene lie, for re-tracing (stored scenes keep
  /// paths as written, relative to their scene file); empty: the working directory.
  vtkSetStringMacro(TextureDirectory);
  vtkGetStringMacro(TextureDirectory);
  ///@}

  ///@{
  /// Exact mode: accumulate the re-traced rays in PostgreSQL (and reuse stored ones). Connection
  /// as for vtkGeodesicPostgreSQLWriter (empty: PG* variables, else the embedded server); the
  /// frames are stored with Label (default "interpolation re-trace").
  vtkSetMacro(StoreRetracedRays, bool);
  vtkGetMacro(StoreRetracedRays, bool);
  vtkBooleanMacro(StoreRetracedRays, bool);
  vtkSetStringMacro(ConnectionString);
  vtkGetStringMacro(ConnectionString);
  vtkSetStringMacro(Label);
  vtkGetStringMacro(Label);
  ///@}

  ///@{
  /// What the last RequestData did: pixels re-traced, how many of them came from the store
  /// instead of the tracer, the id of the stored subset frame (−1: none), and how often the
  /// correspondence has been computed (once per pair of inputs) and how long it last took.
  vtkGetMacro(LastRetracedCount, vtkIdType);
  vtkGetMacro(LastReusedCount, vtkIdType);
  vtkGetMacro(LastStoredFrameId, vtkIdType);
  vtkGetMacro(CorrespondenceBuilds, int);
  vtkGetMacro(CorrespondenceSeconds, double);
  ///@}

  /// Renders every declared time step and writes it with vtkPNGWriter to
  /// "<prefix>_0000.png", "<prefix>_0001.png", …. Returns 1 on success, 0 (with an error) else.
  int WriteSequence(const char* prefix);

protected:
  vtkGeodesicFrameInterpolator();
  ~vtkGeodesicFrameInterpolator() override;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestUpdateExtent(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  int NumberOfIntermediateFrames = 8;
  int CameraPath = AUTOMATIC;
  double MatchTolerance = 1.5;
  double MaxMagnification = 4.0;
  double DepthTolerance = 0.02;
  bool ExactMode = false;
  int RetraceDisagreement = 64;
  char* TextureDirectory = nullptr;
  bool StoreRetracedRays = false;
  char* ConnectionString = nullptr;
  char* Label = nullptr;
  vtkIdType LastRetracedCount = 0;
  vtkIdType LastReusedCount = 0;
  vtkIdType LastStoredFrameId = -1;
  int CorrespondenceBuilds = 0;
  double CorrespondenceSeconds = 0;

private:
  vtkGeodesicFrameInterpolator(const vtkGeodesicFrameInterpolator&) = delete;
  void operator=(const vtkGeodesicFrameInterpolator&) = delete;
  struct Internals;
  std::unique_ptr<Internals> Impl;
};

#endif
