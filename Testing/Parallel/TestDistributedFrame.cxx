// Distributed tracing without MPI: the split of a frame's rows between processes and the exchange
// of neighbour rows for the Jacobians, simulated for several process counts in one process. The
// truth is the single-process frame (FrameTracer::traceRows over all rows): the distributed frame
// must be it, bit for bit. vtkGeodesicDistributedSource alone is tested in
// Testing/Filters/TestDistributedSource.cxx, the MPI runs in mpi-trace.sh and mpi-fault.sh.
#include "DistributedFrame.h"
#include "GeodesicSceneLoading.h"
#include "StoreTestSupport.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <set>

using asrt::RayRecord;
using asrt::RowLayout;
using asrt::RowPartition;
using asrt::testing::recordBits;

namespace
{
/// An odd-sized Kerr frame: rows do not divide evenly among the processes, and the photon ring
/// and the disk's edges give Jacobians that change sign and break off.
constexpr int kW = 37;
constexpr int kH = 29;

asrt::SceneDescription kerrScene()
{
  const std::string path = std::string(ASRT_SOURCE_DIR) + "/Data/scenes/kerr-disk.json";
  asrt::SceneDescription d = asrt::loadScene(nullptr, path.c_str());
  d.camera.width = kW;
  d.camera.height = kH;
  return d;
}

const asrt::FrameTracer& kerrTracer()
{
  static const asrt::FrameTracer tracer(kerrScene());
  return tracer;
}

/// The single-process frame.
const std::vector<RayRecord>& reference()
{
  static const std::vector<RayRecord> records = kerrTracer().traceRows(0, kH);
  return records;
}

/// The first record at which two frames differ in any bit, or -1.
long firstDifference(const std::vector<RayRecord>& a, const std::vector<RayRecord>& b)
{
  for (std::size_t k = 0; k < std::min(a.size(), b.size()); ++k)
    if (recordBits(a[k]) != recordBits(b[k]))
      return static_cast<long>(k);
  return a.size() == b.size() ? -1 : static_cast<long>(std::min(a.size(), b.size()));
}

struct Split
{
  int ranks;
  RowLayout layout;
  int rowsPerBlock;
};

std::string describe(const Split& s)
{
  return std::to_string(s.ranks) + " processes, " +
         (s.layout == RowLayout::Contiguous ? std::string("contiguous")
                                            : "interleaved by " + std::to_string(s.rowsPerBlock));
}

const std::vector<Split>& splits()
{
  static const std::vector<Split> all = {
    { 2, RowLayout::Interleaved, 1 }, { 3, RowLayout::Interleaved, 1 },
    { 4, RowLayout::Interleaved, 1 }, { 4, RowLayout::Interleaved, 3 },
    { 3, RowLayout::Contiguous, 1 },  { 8, RowLayout::Interleaved, 2 },
    { 40, RowLayout::Interleaved, 1 } // more processes than rows: some trace nothing
  };
  return all;
}
}

// -----------------------------------------------------------------------------------------------
// The split of the rows.

TEST(RowPartition, EveryRowBelongsToExactlyOneProcessAndBlocksAreItsTiles)
{
  for (const Split& s : splits())
  {
    SCOPED_TRACE(describe(s));
    const RowPartition p(kH, s.ranks, s.layout, s.rowsPerBlock);
    std::vector<int> owner(kH, -1);
    for (int r = 0; r < s.ranks; ++r)
    {
      const std::vector<int> rows = p.rowsOf(r);
      EXPECT_TRUE(std::is_sorted(rows.begin(), rows.end()));
      for (int j : rows)
      {
        ASSERT_GE(j, 0);
        ASSERT_LT(j, kH);
        EXPECT_EQ(owner[j], -1) << "row " << j << " dealt twice";
        owner[j] = r;
        EXPECT_EQ(p.ownerOfRow(j), r);
      }
    }
    EXPECT_EQ(std::count(owner.begin(), owner.end(), -1), 0) << "a row nobody traces";
    // Blocks, in order, are the rows bottom to top: the stored tiles are in row-major order.
    int next = 0;
    for (int b = 0; b < p.blockCount(); ++b)
    {
      EXPECT_EQ(p.blockBegin(b), next);
      EXPECT_GE(p.blockEnd(b), p.blockBegin(b));
      for (int j = p.blockBegin(b); j < p.blockEnd(b); ++j)
        EXPECT_EQ(owner[j], p.ownerOfBlock(b));
      next = p.blockEnd(b);
    }
    EXPECT_EQ(next, kH);
  }
}

TEST(RowPartition, InterleavedDealsRowJToProcessJModN)
{
  const RowPartition p(1080, 7);
  for (int j = 0; j < 1080; ++j)
    EXPECT_EQ(p.ownerOfRow(j), j % 7);
  EXPECT_EQ(p.blockCount(), 1080);
  const RowPartition blocks(10, 2, RowLayout::Interleaved, 4);
  EXPECT_EQ(blocks.rowsOf(0), (std::vector<int>{ 0, 1, 2, 3, 8, 9 }));
  EXPECT_EQ(blocks.rowsOf(1), (std::vector<int>{ 4, 5, 6, 7 }));
  const RowPartition bands(10, 3, RowLayout::Contiguous);
  EXPECT_EQ(bands.rowsOf(0), (std::vector<int>{ 0, 1, 2 }));
  EXPECT_EQ(bands.rowsOf(1), (std::vector<int>{ 3, 4, 5 }));
  EXPECT_EQ(bands.rowsOf(2), (std::vector<int>{ 6, 7, 8, 9 }));
}

TEST(RowPartition, RowsBorderingAreExactlyTheNeighboursAnotherProcessNeeds)
{
  for (const Split& s : splits())
  {
    SCOPED_TRACE(describe(s));
    const RowPartition p(kH, s.ranks, s.layout, s.rowsPerBlock);
    for (int r = 0; r < s.ranks; ++r)
      for (int q = 0; q < s.ranks; ++q)
      {
        // By definition: rows of r that are a vertical neighbour of some row of q.
        std::set<int> expected;
        if (r != q)
          for (int j : p.rowsOf(q))
            for (int n : { j - 1, j + 1 })
              if (n >= 0 && n < kH && p.ownerOfRow(n) == r)
                expected.insert(n);
        const std::vector<int> got = p.rowsBordering(r, q);
        EXPECT_EQ(std::set<int>(got.begin(), got.end()), expected) << r << " to " << q;
        EXPECT_TRUE(std::is_sorted(got.begin(), got.end()));
      }
  }
}

TEST(RowPartition, RefusesEmptyShapes)
{
  EXPECT_THROW(RowPartition(0, 2), asrt::InvalidParameter);
  EXPECT_THROW(RowPartition(10, 0), asrt::InvalidParameter);
  EXPECT_THROW(RowPartition(10, 2, RowLayout::Interleaved, 0), asrt::InvalidParameter);
}

// -----------------------------------------------------------------------------------------------
// The processes simulated in one: each traces its rows, the neighbour rows go through the packed
// form the processes send each other, and the tiles in order are the single-process frame.

TEST(DistributedFrame, SimulatedProcessesAssembleTheSingleProcessFrameBitForBit)
{
  const asrt::FrameTracer& tracer = kerrTracer();
  // The Jacobians are what the exchange is for: the frame must have plenty, including broken ones.
  std::size_t finite = 0, nan = 0;
  for (const RayRecord& r : reference())
    (std::isnan(r.dudj) ? nan : finite) += 1;
  ASSERT_GT(finite, reference().size() / 4);
  ASSERT_GT(nan, 0u);

  for (const Split& s : splits())
  {
    SCOPED_TRACE(describe(s));
    const RowPartition p(kH, s.ranks, s.layout, s.rowsPerBlock);
    std::vector<std::vector<RayRecord>> own(static_cast<std::size_t>(s.ranks));
    for (int r = 0; r < s.ranks; ++r)
    {
      std::vector<std::pair<int, int>> pixels;
      for (int j : p.rowsOf(r))
        for (int i = 0; i < kW; ++i)
          pixels.emplace_back(i, j);
      own[r] = tracer.traceCentres(pixels);
    }
    // Each process's Jacobians and anti-aliasing from its own rows and what the others send.
    std::vector<std::vector<RayRecord>> done = own;
    for (int r = 0; r < s.ranks; ++r)
    {
      std::vector<asrt::JacobianSample> neighbours;
      for (int q = 0; q < s.ranks; ++q)
      {
        const std::vector<int> rows = p.rowsBordering(q, r);
        std::vector<double> message;
        asrt::packJacobianSamples(own[q], rows, kW, message);
        asrt::unpackJacobianSamples(message, rows, kW, neighbours);
      }
      asrt::FrameTracer::computeJacobians(done[r], neighbours);
      tracer.antialias(done[r], neighbours);
    }
    // The tiles in tile order, each from the process that owns it.
    std::vector<RayRecord> assembled;
    std::vector<std::size_t> taken(static_cast<std::size_t>(s.ranks), 0);
    for (int b = 0; b < p.blockCount(); ++b)
    {
      const int r = p.ownerOfBlock(b);
      const std::size_t n = static_cast<std::size_t>(p.blockEnd(b) - p.blockBegin(b)) * kW;
      assembled.insert(assembled.end(), done[r].begin() + taken[r], done[r].begin() + taken[r] + n);
      taken[r] += n;
    }
    const long diff = firstDifference(assembled, reference());
    EXPECT_EQ(diff, -1) << "first difference at record " << diff;
  }
}

TEST(DistributedFrame, WithoutTheNeighbourRowsTheJacobiansWouldDiffer)
{
  // The exchange is necessary: interleaved rows alone have no vertical neighbours.
  const RowPartition p(kH, 2);
  std::vector<std::pair<int, int>> pixels;
  for (int j : p.rowsOf(0))
    for (int i = 0; i < kW; ++i)
      pixels.emplace_back(i, j);
  std::vector<RayRecord> alone = kerrTracer().traceCentres(pixels);
  std::size_t differing = 0;
  for (const RayRecord& r : alone)
    differing += recordBits(r) != recordBits(reference()[static_cast<std::size_t>(r.j) * kW + r.i]);
  EXPECT_GT(differing, alone.size() / 4);
}

TEST(DistributedFrame, ImageSamplesKeepWhatTheImageShows)
{
  std::vector<double> packed;
  asrt::packImageSamples(reference(), packed);
  ASSERT_EQ(packed.size(), reference().size() * asrt::kImageSampleSize);
  const std::vector<RayRecord> back = asrt::unpackImageSamples(packed);
  ASSERT_EQ(back.size(), reference().size());
  for (std::size_t k = 0; k < back.size(); ++k)
  {
    const RayRecord &a = back[k], &b = reference()[k];
    ASSERT_EQ(a.i, b.i);
    ASSERT_EQ(a.j, b.j);
    ASSERT_EQ(a.objectId, b.objectId);
    ASSERT_EQ(a.imageOrder, b.imageOrder);
    ASSERT_EQ(a.termination, b.termination);
    ASSERT_EQ(a.raysPerPixel, b.raysPerPixel);
    ASSERT_EQ(asrt::testing::bitsOf(a.affineLength), asrt::testing::bitsOf(b.affineLength));
    for (int c = 0; c < 3; ++c)
      ASSERT_EQ(asrt::testing::bitsOf(a.color[c]), asrt::testing::bitsOf(b.color[c]));
  }
  EXPECT_THROW(asrt::unpackImageSamples(std::vector<double>(asrt::kImageSampleSize + 1)),
               asrt::InvalidParameter);
}

TEST(DistributedFrame, StepsPerRankAddUpAndInterleavingBalancesThePhotonRing)
{
  std::vector<std::int64_t> perRow(kH, 0);
  for (const RayRecord& r : reference())
    perRow[r.j] += r.steps;
  const std::int64_t total = std::accumulate(perRow.begin(), perRow.end(), std::int64_t(0));
  auto imbalance = [&](const RowPartition& p)
  {
    const std::vector<std::int64_t> steps = asrt::stepsPerRank(p, perRow);
    EXPECT_EQ(std::accumulate(steps.begin(), steps.end(), std::int64_t(0)), total);
    return static_cast<double>(*std::max_element(steps.begin(), steps.end())) * p.ranks() / total;
  };
  const double interleaved = imbalance(RowPartition(kH, 4));
  const double contiguous = imbalance(RowPartition(kH, 4, RowLayout::Contiguous));
  EXPECT_LT(interleaved, contiguous);
  EXPECT_THROW(asrt::stepsPerRank(RowPartition(kH + 1, 4), perRow), asrt::InvalidParameter);
}
