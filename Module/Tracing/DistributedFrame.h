// Splitting one frame over several processes (ranks): which rows each traces, which rows of its
// neighbours' it needs for the screen-space Jacobians, and the compact forms in which the ranks
// exchange those neighbours and send rank 0 what its image needs. Plain C++: the communication
// itself is the caller's (vtkGeodesicDistributedSource does it through a VTK controller).
//
// Rays near the photon sphere cost many times more integration steps than the rest, and they
// gather in a band of rows around the shadow: contiguous bands of rows give the ranks on that band
// most of the work. Interleaving small blocks of rows deals every band of the image out evenly.
#ifndef asrt_DistributedFrame_h
#define asrt_DistributedFrame_h

#include "RayRecord.h"
#include "asrtTracingModule.h"

#include <cstdint>
#include <vector>

namespace asrt
{
/// How the rows of a frame are dealt to ranks.
enum class RowLayout
{
  Interleaved, ///< blocks of rowsPerBlock rows, block b to rank b mod ranks
  Contiguous   ///< one band of about height/ranks rows per rank, rank 0 at the bottom
};

/// The rows of a frame of `height` rows dealt to `ranks` ranks, in blocks of consecutive rows.
/// Blocks are numbered from the bottom row up; a frame stored by the ranks is stored as one tile
/// per block, so that the stored frame (tiles in tile order) is in row-major order, exactly as a
/// single process stores it.
class ASRTTRACING_EXPORT RowPartition
{
public:
  /// Throws InvalidParameter unless height >= 1, ranks >= 1 and rowsPerBlock >= 1.
  RowPartition(int height, int ranks, RowLayout layout = RowLayout::Interleaved,
               int rowsPerBlock = 1);

  int height() const { return this->Height; }
  int ranks() const { return this->Ranks; }
  RowLayout layout() const { return this->Layout; }
  int blockCount() const;
  /// Rows [blockBegin(b), blockEnd(b)) of block b (empty for a contiguous rank without rows).
  int blockBegin(int block) const;
  int blockEnd(int block) const;
  int ownerOfBlock(int block) const;
  int ownerOfRow(int row) const;
  /// The blocks of `rank`, bottom to top.
  std::vector<int> blocksOf(int rank) const;
  /// The rows of `rank`, bottom to top.
  std::vector<int> rowsOf(int rank) const;
  /// Rows of `rank` with a vertical neighbour (row ± 1) that belongs to `peer`: what `rank` sends
  /// `peer` for its Jacobians, and (the relation being symmetric) what it receives from `peer`
  /// is rowsBordering(peer, rank). Bottom to top.
  std::vector<int> rowsBordering(int rank, int peer) const;

private:
  int Height, Ranks, RowsPerBlock;
  RowLayout Layout;
};

/// Doubles per pixel in packJacobianSamples() (u, v, object id, image order, termination).
constexpr int kJacobianSampleSize = 5;
/// Doubles per pixel in packImageSamples() (i, j, colour, object id, image order, path length,
/// termination, rays per pixel): what recordsToImage reads.
constexpr int kImageSampleSize = 10;

/// Appends the Jacobian inputs of `records` whose row is one of `rows` (both bottom to top, the
/// records row-major) to `out`, kJacobianSampleSize doubles per pixel, row after row.
ASRTTRACING_EXPORT void packJacobianSamples(const std::vector<RayRecord>& records,
                                            const std::vector<int>& rows, int width,
                                            std::vector<double>& out);
/// The inverse: the samples of rows `rows` (width pixels each), appended to `out`, for
/// FrameTracer::computeJacobians(records, neighbours), which then gives every record whose
/// vertical neighbours are among the records or the samples its whole-frame Jacobians.
ASRTTRACING_EXPORT void unpackJacobianSamples(const std::vector<double>& samples,
                                              const std::vector<int>& rows, int width,
                                              std::vector<JacobianSample>& out);

/// Appends what the image of `records` needs, kImageSampleSize doubles per record.
ASRTTRACING_EXPORT void packImageSamples(const std::vector<RayRecord>& records,
                                         std::vector<double>& out);
/// The inverse: records carrying only the fields packImageSamples keeps.
ASRTTRACING_EXPORT std::vector<RayRecord> unpackImageSamples(const std::vector<double>& samples);

/// The integration steps each rank would take for a frame whose rows cost `stepsPerRow` (summed
/// over each row's pixels), split as `partition` splits it: the load balance of a split, by
/// simulation, without running the ranks.
ASRTTRACING_EXPORT std::vector<std::int64_t> stepsPerRank(
  const RowPartition& partition, const std::vector<std::int64_t>& stepsPerRow);
}

#endif
