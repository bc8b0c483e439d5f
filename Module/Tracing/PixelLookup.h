// Finding a frame's pixels by (i, j) among traced records and samples from elsewhere: a dense grid
// over their bounding box when they fill much of it (a frame, bands or interleaved rows of one), a
// hash map when they are scattered (a pixel subset). Internal to ASRT::Tracing.
#ifndef asrt_PixelLookup_h
#define asrt_PixelLookup_h

#include "FrameTracer.h" // kParallelRecords
#include "RayRecord.h"

#include <algorithm>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace asrt
{
/// The samples of `records` followed by `extra`; where a pixel appears twice, its first appearance
/// counts.
class PixelLookup
{
public:
  PixelLookup(const std::vector<RayRecord>& records, const std::vector<JacobianSample>& extra)
  {
    this->Samples.resize(records.size());
    const long n = static_cast<long>(records.size());
#pragma omp parallel for schedule(static) if (n > kParallelRecords)
    for (long k = 0; k < n; ++k)
      this->Samples[static_cast<std::size_t>(k)] =
        jacobianSample(records[static_cast<std::size_t>(k)]);
    this->Samples.insert(this->Samples.end(), extra.begin(), extra.end());
    if (this->Samples.empty())
      return;
    this->IMin = this->IMax = this->Samples[0].i;
    this->JMin = this->JMax = this->Samples[0].j;
    for (const JacobianSample& s : this->Samples)
    {
      this->IMin = std::min(this->IMin, s.i);
      this->IMax = std::max(this->IMax, s.i);
      this->JMin = std::min(this->JMin, s.j);
      this->JMax = std::max(this->JMax, s.j);
    }
    this->Width = std::int64_t(this->IMax) - this->IMin + 1;
    const std::int64_t box = this->Width * (std::int64_t(this->JMax) - this->JMin + 1);
    this->Dense = box <= 4 * static_cast<std::int64_t>(this->Samples.size());
    if (this->Dense)
      this->Grid.assign(static_cast<std::size_t>(box), -1);
    for (std::size_t k = 0; k < this->Samples.size(); ++k)
    {
      const JacobianSample& s = this->Samples[k];
      if (this->Dense)
      {
        std::int64_t& slot = this->Grid[this->slot(s.i, s.j)];
        if (slot < 0)
          slot = static_cast<std::int64_t>(k);
      }
      else
        this->Index.emplace(key(s.i, s.j), k);
    }
  }

  /// The sample of pixel (i, j), null if there is none.
  const JacobianSample* at(int i, int j) const
  {
    if (this->Samples.empty())
      return nullptr;
    if (this->Dense)
    {
      if (i < this->IMin || i > this->IMax || j < this->JMin || j > this->JMax)
        return nullptr;
      const std::int64_t k = this->Grid[this->slot(i, j)];
      return k < 0 ? nullptr : &this->Samples[static_cast<std::size_t>(k)];
    }
    const auto it = this->Index.find(key(i, j));
    return it == this->Index.end() ? nullptr : &this->Samples[it->second];
  }

private:
  static std::int64_t key(int i, int j)
  {
    return (static_cast<std::int64_t>(j) << 32) ^ static_cast<std::uint32_t>(i);
  }
  std::size_t slot(int i, int j) const
  {
    return static_cast<std::size_t>((j - this->JMin) * this->Width + (i - this->IMin));
  }

  std::vector<JacobianSample> Samples;
  int IMin = 0, IMax = -1, JMin = 0, JMax = -1;
  std::int64_t Width = 0;
  bool Dense = false;
  std::vector<std::int64_t> Grid;
  std::unordered_map<std::int64_t, std::size_t> Index;
};
}

#endif
