// Making a movie along a path at a quality target: the one implementation behind `asrt movie` and
// vtkGeodesicMovieSource. The path (a ramp of mass, spin or charge, an orbit of the camera, or any
// setting of a vtkGeodesicSource per frame) gives every frame's scene; the plan (MoviePlan.h)
// chooses the key frames; key frames are traced whole, or read from the store; the others are
// interpolated per pixel between the nearest keys (PathInterpolation.h) and completed to the
// target with the pixels it needs re-traced, read from the store where it has them.
//
// Reuse. A whole frame is found by its identity (the scene at the frame's parameters), whoever
// stored it. An interpolated frame's keys are recorded with it in the store
// (RayStore::recordInterpolatedFrame, by its recipe: the target and what it is held to); a later
// movie whose frames include it and those keys makes it again between exactly those keys,
// whatever keys its own plan has, and plans only the other frames. The pixels an interpolated frame
// re-traces are stored as subset frames: the scene at the frame's parameters with a "subset" naming
// the pixels (count and digest), so they never pass for the whole frame. completePathFrame asks for
// two lists of pixels, each a function of the keys and of the records traced before; the same keys
// therefore ask for the same lists. So the plan is stable under storing its own whole frames
// (MoviePlan.h), and a denser movie over a stored path is offered the stored frames as its only
// keys (planBetweenStored), its old interpolated frames then served whole by the store: which of
// them are is found by making them from the store alone before planning, and the frames so made are
// kept (within a memory bound) for frame() to hand out rather than made again. The pictures a
// movie encodes from a frame are stored with what it was made from (storePictures), and a frame
// whose pictures are stored is written from them, nothing of it read or made (storedPictures).
//
// Chains. The pixels that frames recorded between a frame's inner keys re-traced (read back from
// the store, RayStore::readSubsetRecords) join its pixels' chains of nodes (PathOptions::samples):
// a denser movie over a stored path re-traces fewer of its new frames' pixels. Only frames the
// store records as made from their keys alone serve so, and a frame made through them is recorded
// by another recipe (interpolationRecipe's chained one): whenever it is made again, it finds the
// same frames to run through, and asks for the same pixels.
//
// Learning. The plan starts from a prior of the re-trace share (SpacingShareModel) and of the
// costs, in rays integrated: a whole frame's, a re-trace's (one ray a re-traced pixel, and the
// rays of its edges: neighbours, midpoints, anti-aliasing samples) and interpolating a frame's
// (MovieCostPrior, measured on the bench's movies). Keys to trace are made coarse first; each one
// is interpolated between the whole frames around it and completed against its own records,
// which measures the share its gap needed and the rays re-tracing those pixels would integrate
// (RetraceRays.h) without tracing a ray, and the rest is planned again (planProgressively).
// Running the same movie again plans from the prior with the keys stored: where that would add
// keys, the stored frames as the only keys (the first run's plan) serve every frame for nothing,
// and win.
#ifndef asrt_GeodesicMovie_h
#define asrt_GeodesicMovie_h

#include "AsrtTypes.h"
#include "MoviePlan.h"
#include "RayRecord.h"
#include "SceneDescription.h"
#include "asrtFiltersModule.h"

#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

class vtkGeodesicSource;

namespace asrt
{
class RayStore;
struct MovieMaking;

/// A path parameter's text, as a frame describes itself ("%.6g": 0.675, 1e-05).
ASRTFILTERS_EXPORT std::string formatParameter(double v);

/// A camera: eye, focal point and up.
struct CameraPose
{
  Vec3 position = Vec3::Zero();
  Vec3 focalPoint = Vec3::Zero();
  Vec3 viewUp = Vec3::UnitZ();
};

/// The camera of a scene's JSON text (its images are not read). Throws InvalidParameter for an
/// invalid scene.
ASRTFILTERS_EXPORT CameraPose sceneCameraOfText(const std::string& sceneText);
/// The pose turned by `degrees` about the z axis through the origin (counter-clockwise seen from
/// +z): the eye keeps its distance and height, so the hole looks the same but the sky and the
/// objects move.
ASRTFILTERS_EXPORT CameraPose turnedAboutZ(const CameraPose& pose, double degrees);
/// The angle of frame k of n on an orbit through `degrees`: a full turn (±360) closes on itself
/// (k·360/n, the last frame one step short of the first); a partial one runs from 0 to `degrees`
/// inclusive.
ASRTFILTERS_EXPORT double orbitAngle(int k, int n, double degrees);
/// Sets the source's camera overrides to the pose.
ASRTFILTERS_EXPORT void setCamera(vtkGeodesicSource* source, const CameraPose& pose);

/// A movie's path: its parameter per frame, and the setting of the source that gives each frame.
struct MoviePath
{
  std::string parameter; ///< "mass", "spin", "charge", "orbit angle" or "camera key"
  std::vector<double> s;
  std::vector<std::function<void(vtkGeodesicSource*)>> apply;
};

/// Sets `parameter` ("mass", "spin" or "charge") of the source to v. Throws InvalidParameter for
/// another parameter.
ASRTFILTERS_EXPORT void setRampParameter(vtkGeodesicSource* source, const std::string& parameter,
                                         double v);

/// The most frames of a movie.
constexpr int kMaxMovieFrames = 10000;

/// `parameter` ("mass", "spin" or "charge") from `from` to `to` over `n` frames, frame k at
/// from + (to − from) k / (n − 1) (asrt trace --sweep's formula, so that its frames are these).
/// Throws InvalidParameter naming the field: an unknown parameter, n outside [2, kMaxMovieFrames],
/// FROM or TO not finite, or equal.
ASRTFILTERS_EXPORT MoviePath rampMoviePath(const std::string& parameter, double from, double to,
                                           int n);
/// The camera `pose` turned about the hole's axis through `degrees` over `n` frames (orbitAngle).
/// Throws InvalidParameter for n outside [2, kMaxMovieFrames], or degrees zero, not finite or
/// above 360 in magnitude.
ASRTFILTERS_EXPORT MoviePath orbitMoviePath(const CameraPose& pose, double degrees, int n);

/// One frame of the movie: where it lies on the path and which scene it is.
struct MovieFrame
{
  double s = 0;
  std::string describe;      ///< e.g. "mass = 0.675"
  std::string sceneText;     ///< the effective scene text at the frame's parameters
  SceneDescription identity; ///< without textures: the frame's identity in the store
  std::optional<std::int64_t> storedId;
};

/// The frames' scenes of `source` (its scene and overrides) along the path, each checked (a
/// camera sent inside the horizon, a spin ramped past the mass) before anything is traced; the
/// textures, which a path does not change, read at the first frame only. Throws
/// InvalidParameter "frame K (P = V): <the source's error>".
ASRTFILTERS_EXPORT std::vector<MovieFrame> movieFrames(vtkGeodesicSource* source,
                                                       const MoviePath& path);

/// Thrown when the movie's `cancelled` callback asked to stop.
struct MovieCancelled : std::runtime_error
{
  MovieCancelled()
    : std::runtime_error("the movie was cancelled")
  {
  }
};

/// How one frame was made.
struct MovieFrameReport
{
  FrameMethod method = FrameMethod::Key;
  /// Against the converged picture (MovieSettings::holdToConverged), else against the frame
  /// traced at the frame's parameters.
  double estimatedPsnr = std::numeric_limits<double>::infinity();
  /// The bound on the settings' own PSNR against the converged picture: for an interpolated
  /// frame its inner keys' probes pooled, for a whole frame its own where it was measured
  /// (infinite where it was not).
  double settingsPsnr = std::numeric_limits<double>::infinity();
  double shareRetraced = 0; ///< of its pixels traced for it (1 for a frame traced whole)
  /// Integrated for this frame, this time: a re-traced subset counts the edge neighbours that
  /// FrameTracer::tracePixels traces and drops (FrameTracer::raysIntegrated).
  double raysTraced = 0;
  /// Read from the store or the cache for it: the rays its records hold (their raysPerPixel).
  double raysReused = 0;
};

struct MovieSettings
{
  /// The PSNR in dB every interpolated frame is to reach, in (0, kMaxQualityTargetDb].
  double quality = 35;
  /// Whether `quality` is against the converged picture (SettingsError.h: each key an
  /// interpolated frame uses has its own error against its converged picture measured by probe
  /// pixels traced converged, stored and reused as a re-traced subset is), or against the frame
  /// traced at the frame's parameters with the movie's settings.
  bool holdToConverged = true;
  /// Where the scene's relative texture paths lie (its file's directory).
  std::string textureDirectory;
  /// The label of frames stored.
  std::string label;
  /// Keep the pixels re-traced for interpolated frames in memory too, so that making a frame again
  /// (scrubbing) traces nothing even without a store.
  bool cacheRetraced = false;
  /// The bytes of whole frames' records kept in memory beyond those a frame in the making uses;
  /// the least recently used frames that are stored leave first and are read again when needed
  /// (at 1920×1080 a frame's records take about 550 MB). 0: a GiB or 4 frames, whichever is more,
  /// and at most a quarter of the memory a read may take (defaultMemoryLimit).
  double keptFrameBytes = 0;
  /// As keptFrameBytes, for the whole frames not stored (no store), which cannot be read back: the
  /// least recently used leave first, those that no interpolated frame is made from before the
  /// others, and a frame let go is traced again if it is needed again (a 61-frame movie at
  /// 1920×1080 traced whole would need about 36 GB). 0: 2 GiB or 8 frames, whichever is more, and
  /// at most half the memory a read may take.
  double unstoredFrameBytes = 0;
  /// Asked during traces: true stops the movie (MovieCancelled).
  std::function<bool()> cancelled;
  /// Called with the fraction done of a whole frame being traced.
  std::function<void(double)> traceProgress;
  /// Called with every whole frame traced, before it is stored or used (e.g. to refuse one with
  /// too many failed rays by throwing).
  std::function<void(const std::vector<RayRecord>&, int frame)> checkTraced;
  /// The pictures (`pictureFormats`, as storedPictures() is asked for them) of each whole frame
  /// this movie traces, encoded as soon as it is traced. storedPictures() then hands them out (and
  /// stores them, with a store), so that the frame's records need not be kept, read back from the
  /// store or traced again, until the frame's turn comes (at 1920×1080 a frame's records are about
  /// 550 MB, its PNG under 1 MB, its VTI about 25 MB). Pictures kept beyond a quarter of the memory
  /// a read may take are let go, the earliest first: those frames are made from their records
  /// again.
  std::vector<std::string> pictureFormats;
  std::function<std::vector<std::string>(const std::vector<RayRecord>&)> encodePictures;
};

/// The adaptive cap a movie lowers its rendering to where the default reaches its target with
/// room to spare (MovieMaker::withRenderingForTarget): a 2 × 2 pattern, whose even side lets the
/// default frames' probes be anti-aliased again at it (FrameTracer::antialiasAgain). On the
/// bench's movies at 200 × 200 it costs 0.84–0.90 of the default's CPU a frame and scores
/// 3.2–3.8 dB lower against converged frames (bench/REPORT.md, "Movies").
constexpr int kLoweredRaysPerPixel = 5;

/// The adaptive cap a movie raises its rendering to where the default does not reach its target
/// (MovieMaker::withRenderingForTarget), before the accurate preset: a 4 × 4 pattern, even as
/// kLoweredRaysPerPixel's. On the bench's mass ramp and Fig. 1's orbit at 200 × 200 it scores
/// 42.1 and 40.4 dB mean against 8 × 8 references, 0.9–1.0 dB below the accurate preset, for
/// 0.61–0.64 of its CPU (bench/REPORT.md, "Movies"; against 4 × 4 it would seem better than
/// the accurate preset: settingsReferenceSide).
constexpr int kRaisedRaysPerPixel = 17;

/// How a movie's rendering was chosen for its target (MovieMaker::withRenderingForTarget).
struct RenderingChoice
{
  enum class Change
  {
    Kept,    ///< the default rendering (or one asked for, not judged)
    Lowered, ///< kLoweredRaysPerPixel between the first and last frames
    Raised,  ///< kRaisedRaysPerPixel
    Accurate ///< the accurate preset
  };
  Change change = Change::Kept;
  /// What the default rendering reaches against the converged picture: the lower of the first
  /// and last frames' estimates (infinite where not judged).
  double defaultReach = std::numeric_limits<double>::infinity();
  /// What the adaptive cap chosen (Lowered, Raised) reaches, as defaultReach; for Accurate, what
  /// kRaisedRaysPerPixel reached (infinite where it was not measured).
  double reach = std::numeric_limits<double>::infinity();
};

/// One movie: its plan, made once, and its frames, each made on demand.
class ASRTFILTERS_EXPORT MovieMaker
{
public:
  /// `frames` at least 2, of one size; `store` may be null (nothing stored or reused) and must
  /// outlive the maker. Throws InvalidParameter for a quality target out of range or NaN.
  MovieMaker(std::vector<MovieFrame> frames, std::string parameter, RayStore* store,
             MovieSettings settings);
  ~MovieMaker();
  MovieMaker(const MovieMaker&) = delete;
  MovieMaker& operator=(const MovieMaker&) = delete;

  /// The plan: made at the first call (looking up the stored frames).
  const MoviePlan& plan();
  const std::vector<MovieFrame>& frames() const { return this->Frames; }
  /// The re-trace share estimate: the prior, and what the keys made measured.
  const SpacingShareModel& shareModel() const;
  const std::string& parameter() const { return this->Parameter; }
  int width() const { return this->Width; }
  int height() const { return this->Height; }

  /// Whether the movie's rendering is judged against its target: held to converged, and its
  /// frames' rendering the default one (a rendering asked for is kept).
  bool judgesRendering() const;
  /// The movie at the rendering its target asks for, where it is judged (judgesRendering): what
  /// the default rendering reaches against the converged picture is measured on the first and
  /// last frames (both are keys of every plan, made whole here, traced and stored or read; their
  /// probes traced converged, SettingsError.h), and so is what the adaptive caps
  /// kLoweredRaysPerPixel and kRaisedRaysPerPixel would reach (the same probes anti-aliased again
  /// at each cap, FrameTracer::antialiasAgain, a few hundred rays). A rendering is enough where it
  /// reaches the target plus 1 dB: the default and the higher cap by their probes' estimate, the
  /// lower cap by their bound (SettingsError::psnr), so that the default is left for a cheaper
  /// rendering only where the probes vouch for it.
  ///  - The default enough, and the lower cap too (with `lower`): the same movie at the lower cap,
  ///    its first and last frames the ones made here (adopted).
  ///  - The default not enough (with `raise`): the same movie at the higher cap where that is
  ///    enough, its first and last frames anti-aliased again from the ones made here; else with
  ///    the accurate preset.
  /// Null where the default is kept; `source` (the frames' source as movieFrames took them along
  /// `path`) is left set to the rendering returned. `choice` says what was chosen and measured.
  std::unique_ptr<MovieMaker> withRenderingForTarget(vtkGeodesicSource* source,
                                                     const MoviePath& path, RenderingChoice& choice,
                                                     bool raise = true, bool lower = true);

  /// Makes (or reads) every key frame of the plan, calling `afterEach` with the frame after each
  /// one it traces (those stored are read when a frame needs them, unannounced). When the plan
  /// traces whole frames, they are made coarse first and the plan learns from each
  /// (planProgressively): the rays it took, and the share that interpolating it between the whole
  /// frames around it would have re-traced, measured against its own records. The plan is final
  /// afterwards (frame() makes the keys first if this was not called).
  void makeKeys(const std::function<void(int frame)>& afterEach = {});
  /// Frame k's records, one per pixel in pixel order (record p is pixel (p mod width, p / width)).
  /// Key frames are traced or read once and kept; an interpolated frame's re-traced pixels are
  /// read from the store (or the memory cache) when they were traced before.
  std::vector<RayRecord> frame(int k, MovieFrameReport& report);
  /// As frame(), the records handed to `use` instead of returned: a whole frame's are the kept
  /// ones, not a copy (at 1920×1080 a copy is half a gigabyte of fresh memory). `use` must not
  /// call back into this maker.
  void useFrame(int k, MovieFrameReport& report,
                const std::function<void(const std::vector<RayRecord>&)>& use);

  /// Frame k's pictures in `formats` (each an encoding and its version, e.g. "png.1"), as a movie
  /// stored them after making the frame (storePictures): of its whole stored frame, or, for a frame
  /// the store records as interpolated by this movie's recipe between stored frames of this movie,
  /// made between exactly those (RayStore::readPicture). Null for a frame that is neither, or
  /// where any format is missing: then frame() makes it. Otherwise `report` is what frame()
  /// reported when it made the frame, its rays counted as read, and neither its keys nor its
  /// re-traced pixels are read. Once the keys are made (makeKeys), the pictures a whole frame
  /// traced by this movie got then (MovieSettings::encodePictures) are handed out, once, with the
  /// report frame() gives, and stored; without a store, they are all it hands out.
  std::optional<std::vector<std::string>> storedPictures(int k,
                                                         const std::vector<std::string>& formats,
                                                         MovieFrameReport& report);
  /// Stores frame k's pictures `bytes` in `formats`, encoded from the records frame() gave with
  /// `report`, where the store holds what it was made from: the frame stored whole, or its keys
  /// and its record as interpolated between them. Nothing without a store.
  void storePictures(int k, const std::vector<std::string>& formats,
                     const std::vector<std::string>& bytes, const MovieFrameReport& report);

  /// Rays integrated so far by this maker (anti-aliasing's extra rays, and the edge neighbours a
  /// re-traced subset traces and drops, counted).
  double raysTraced() const { return this->RaysTraced; }
  /// Rays of the frames made, traced or read: what the movie cost in all.
  double raysOfMovie() const { return this->RaysOfMovie; }
  /// Rays of the whole frames made and how many (for the rays a whole frame takes).
  double raysOfKeys() const { return this->RaysOfKeys; }
  int wholeCount() const { return this->WholeCount; }
  /// The whole frames whose records are in memory now (MovieSettings::keptFrameBytes and
  /// unstoredFrameBytes bound them).
  std::size_t wholeFramesKept() const;

private:
  friend struct MovieMaking;
  /// The frames not stored whole that the store records as interpolated, by this movie's recipe,
  /// between keys that are frames of this movie and stored (their storedId looked up).
  void findRecorded();
  /// Frame k's records (frame()): the kept whole frame's, or `made` holding those made for it.
  const std::vector<RayRecord>& madeFrame(int k, MovieFrameReport& report,
                                          std::vector<RayRecord>& made);
  /// Fills the rays, settings and share of `report` for whole frame k, made.
  void reportWhole(int k, MovieFrameReport& report) const;
  /// What frame k's settings reach against its converged picture, as a PSNR: its own error
  /// estimated (not bounded) from its probes traced converged (SettingsError.h). Makes frame k
  /// whole and its probes, traced and stored or read, as the movie would.
  double settingsReach(int k);
  /// Frame k's storedId looked up before the plan is (which looks up every frame's): a stored
  /// frame is read, not traced again.
  void lookUpStored(int k);
  /// What frame k's settings would reach at the rendering of `other` (frame k at another
  /// adaptive cap): its estimate as settingsReach gives it, or with `bound` its bound
  /// (SettingsError::psnr). Frame k is made whole as settingsReach makes it, its probes
  /// anti-aliased again.
  double settingsReachAt(int k, const MovieFrame& other, bool bound);
  /// Frame k anti-aliased again from `from`'s (a maker of the same movie at another adaptive cap,
  /// FrameTracer::antialiasAgain), made by `from` if it has not made it, its records moved out of
  /// `from`; nothing where this movie has it, or the store does.
  void deriveWhole(MovieMaker& from, int k);
  /// Takes frame k from `from` (a maker of the same movie at another rendering): its identity, its
  /// records (made by `from` if it has not made them, moved out of it) and what `from` measured of
  /// it, counted as this movie's.
  void adoptWhole(MovieMaker& from, int k);
  struct Internals;
  std::vector<MovieFrame> Frames;
  std::string Parameter;
  RayStore* Store = nullptr;
  MovieSettings Settings;
  int Width = 0, Height = 0;
  std::optional<MoviePlan> Plan;
  double RaysTraced = 0, RaysOfMovie = 0, RaysOfKeys = 0;
  int WholeCount = 0;
  std::unique_ptr<Internals> Impl;
};
}

#endif
