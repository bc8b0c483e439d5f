// The keys' leave-one-out errors: each inner key of a path frame predicted from the other keys, as
// though it were a frame between them, and compared with its own colours. Where a key is badly
// predicted from its neighbours, a frame between it and the next is likely badly predicted too:
// a cross-validation of the interpolation on the keys themselves, for no ray traced. The errors
// weigh the estimate's order of re-tracing within each way of predicting.
#ifndef asrt_LeaveOneOut_h
#define asrt_LeaveOneOut_h

#include "PathInterpolation.h"

namespace asrt
{
/// The leave-one-out errors of keys (leaveOneOutError, before its dilation), kept for the frames
/// that follow: a key's is the same for every frame on either side of it. Kept by the content of
/// the key left out and of the keys that predict it, and by how they predict. At most `capacity`
/// are kept (4 bytes a pixel), the least recently used going first. Thread-safe.
class ASRTINTERPOLATION_EXPORT LeaveOneOutCache
{
public:
  explicit LeaveOneOutCache(std::size_t capacity = 4);
  /// The errors kept under `key`, `make()` where none are.
  std::shared_ptr<const std::vector<float>> errors(std::uint64_t key,
                                                   const std::function<std::vector<float>()>& make);
  /// How many `errors` made (rather than found kept) so far.
  std::size_t made() const;

private:
  KeptResults<std::uint64_t, std::vector<float>> Kept;
};

/// Of the inner keys around t, each one that has a key on either side of it predicted from the
/// other keys at its own parameter (interpolateAlongPath without it), and the squared colour
/// difference to its own colours (levels² of 255, summed over the channels): per pixel, the
/// largest over those keys and over the pixels within `radius`, a dilation so that an edge
/// that moves between the keys is covered at t. Empty when neither inner key can be left out.
ASRTINTERPOLATION_EXPORT std::vector<float> leaveOneOutError(const std::vector<PathKey>& keys,
                                                             double t, int width, int height,
                                                             const Scene& scene,
                                                             const PathOptions& options,
                                                             int radius = 2);

/// The factor a leave-one-out error L puts on a predicted pixel's estimate: 1 + L / 100 (levels²
/// of 255). Where the keys predict each other to within a few levels the estimate stands; where
/// they miss by tens of levels, the pixel moves up the order of re-tracing by as much.
inline float leaveOneOutWeight(float L)
{
  return 1.0f + L / 100.0f;
}

/// Weighs each predicted pixel's finite estimate by leaveOneOutWeight of its leave-one-out error
/// `L` (one per pixel; empty: nothing to weigh), then scales each way of predicting's estimates so
/// that their sum is the same as before: the order within a way changes, the way's total, which
/// completePathFrame's probes calibrate, does not. The pixels `unweighed` marks (one flag per
/// pixel; empty: none) keep their estimates and count in no total.
ASRTINTERPOLATION_EXPORT void weighByLeaveOneOut(PathFrame& f, const std::vector<float>& L,
                                                 const std::vector<std::uint8_t>& unweighed = {});
}

#endif
