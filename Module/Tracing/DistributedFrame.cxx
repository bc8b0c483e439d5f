#include "DistributedFrame.h"

#include <algorithm>
#include <string>

namespace asrt
{
RowPartition::RowPartition(int height, int ranks, RowLayout layout, int rowsPerBlock)
  : Height(height)
  , Ranks(ranks)
  , RowsPerBlock(rowsPerBlock)
  , Layout(layout)
{
  if (height < 1 || ranks < 1 || rowsPerBlock < 1)
    throw InvalidParameter("a row partition needs height, ranks and rows per block of at least 1 "
                           "(got " +
                           std::to_string(height) + ", " + std::to_string(ranks) + ", " +
                           std::to_string(rowsPerBlock) + ")");
}

int RowPartition::blockCount() const
{
  if (this->Layout == RowLayout::Contiguous)
    return this->Ranks;
  return (this->Height + this->RowsPerBlock - 1) / this->RowsPerBlock;
}

int RowPartition::blockBegin(int block) const
{
  if (this->Layout == RowLayout::Contiguous)
    return static_cast<int>(static_cast<long long>(this->Height) * block / this->Ranks);
  return std::min(this->Height, block * this->RowsPerBlock);
}

int RowPartition::blockEnd(int block) const
{
  return this->blockBegin(block + 1);
}

int RowPartition::ownerOfBlock(int block) const
{
  return this->Layout == RowLayout::Contiguous ? block : block % this->Ranks;
}

int RowPartition::ownerOfRow(int row) const
{
  if (this->Layout == RowLayout::Interleaved)
    return (row / this->RowsPerBlock) % this->Ranks;
  // The band holding `row`: the last rank whose band starts at or below it.
  int rank = static_cast<int>(static_cast<long long>(row) * this->Ranks / this->Height);
  while (rank + 1 < this->Ranks && this->blockBegin(rank + 1) <= row)
    ++rank;
  while (rank > 0 && this->blockBegin(rank) > row)
    --rank;
  return rank;
}

std::vector<int> RowPartition::blocksOf(int rank) const
{
  std::vector<int> blocks;
  for (int b = 0; b < this->blockCount(); ++b)
    if (this->ownerOfBlock(b) == rank)
      blocks.push_back(b);
  return blocks;
}

std::vector<int> RowPartition::rowsOf(int rank) const
{
  std::vector<int> rows;
  for (int b : this->blocksOf(rank))
    for (int j = this->blockBegin(b); j < this->blockEnd(b); ++j)
      rows.push_back(j);
  return rows;
}

std::vector<int> RowPartition::rowsBordering(int rank, int peer) const
{
  std::vector<int> rows;
  if (rank == peer)
    return rows;
  for (int j : this->rowsOf(rank))
    if ((j > 0 && this->ownerOfRow(j - 1) == peer) ||
        (j + 1 < this->Height && this->ownerOfRow(j + 1) == peer))
      rows.push_back(j);
  return rows;
}

void packJacobianSamples(const std::vector<RayRecord>& records, const std::vector<int>& rows,
                         int width, std::vector<double>& out)
{
  // Both lists run bottom to top, so one pass over the records finds every row.
  std::size_t k = 0;
  for (int j : rows)
  {
    while (k < records.size() && records[k].j < j)
      ++k;
    if (k + static_cast<std::size_t>(width) > records.size() || records[k].j != j)
      throw InvalidParameter("packJacobianSamples: row " + std::to_string(j) +
                             " is not among the records");
    for (int i = 0; i < width; ++i, ++k)
    {
      const RayRecord& r = records[k];
      out.insert(out.end(),
                 { r.u, r.v, static_cast<double>(r.objectId), static_cast<double>(r.imageOrder),
                   static_cast<double>(static_cast<int>(r.termination)) });
    }
  }
}

void unpackJacobianSamples(const std::vector<double>& samples, const std::vector<int>& rows,
                           int width, std::vector<JacobianSample>& out)
{
  if (samples.size() != rows.size() * static_cast<std::size_t>(width) * kJacobianSampleSize)
    throw InvalidParameter("unpackJacobianSamples: " + std::to_string(samples.size()) +
                           " values for " + std::to_string(rows.size()) + " rows of " +
                           std::to_string(width) + " pixels");
  const double* s = samples.data();
  for (int j : rows)
    for (int i = 0; i < width; ++i, s += kJacobianSampleSize)
      out.push_back({ i, j, s[0], s[1], static_cast<std::int32_t>(s[2]),
                      static_cast<std::int32_t>(s[3]),
                      static_cast<Termination>(static_cast<int>(s[4])) });
}

void packImageSamples(const std::vector<RayRecord>& records, std::vector<double>& out)
{
  out.reserve(out.size() + records.size() * kImageSampleSize);
  for (const RayRecord& r : records)
    out.insert(out.end(),
               { static_cast<double>(r.i), static_cast<double>(r.j), r.color[0], r.color[1],
                 r.color[2], static_cast<double>(r.objectId), static_cast<double>(r.imageOrder),
                 r.affineLength, static_cast<double>(static_cast<int>(r.termination)),
                 static_cast<double>(r.raysPerPixel) });
}

std::vector<RayRecord> unpackImageSamples(const std::vector<double>& samples)
{
  if (samples.size() % kImageSampleSize != 0)
    throw InvalidParameter("unpackImageSamples: " + std::to_string(samples.size()) +
                           " values are not whole pixels");
  std::vector<RayRecord> records(samples.size() / kImageSampleSize);
  const double* s = samples.data();
  for (RayRecord& r : records)
  {
    r.i = static_cast<std::int32_t>(s[0]);
    r.j = static_cast<std::int32_t>(s[1]);
    r.color = Color(s[2], s[3], s[4]);
    r.objectId = static_cast<std::int32_t>(s[5]);
    r.imageOrder = static_cast<std::int32_t>(s[6]);
    r.affineLength = s[7];
    r.termination = static_cast<Termination>(static_cast<int>(s[8]));
    r.raysPerPixel = static_cast<std::int32_t>(s[9]);
    s += kImageSampleSize;
  }
  return records;
}

std::vector<std::int64_t> stepsPerRank(const RowPartition& partition,
                                       const std::vector<std::int64_t>& stepsPerRow)
{
  if (static_cast<int>(stepsPerRow.size()) != partition.height())
    throw InvalidParameter("stepsPerRank: " + std::to_string(stepsPerRow.size()) +
                           " rows given for a partition of " + std::to_string(partition.height()));
  std::vector<std::int64_t> steps(static_cast<std::size_t>(partition.ranks()), 0);
  for (int j = 0; j < partition.height(); ++j)
    steps[static_cast<std::size_t>(partition.ownerOfRow(j))] +=
      stepsPerRow[static_cast<std::size_t>(j)];
  return steps;
}
}
