// Results kept by a key, the least recently used going first: the frames along a movie path ask
// again and again for what their keys give alike (the keys' correspondences, their leave-one-out
// errors). Thread-safe; a result is made outside the lock, so two threads asking at once for the
// same missing key may both make it, alike.
#ifndef asrt_KeptResults_h
#define asrt_KeptResults_h

#include <algorithm>
#include <cstddef>
#include <list>
#include <memory>
#include <mutex>
#include <utility>

namespace asrt
{
/// At most `capacity` results of type Value, each under its Key (compared with ==).
template<class Key, class Value>
class KeptResults
{
public:
  explicit KeptResults(std::size_t capacity)
    : Capacity(std::max<std::size_t>(capacity, 1))
  {
  }

  /// The result kept under `key`, else `make()`'s, then kept (the least recently used let go).
  template<class Make>
  std::shared_ptr<const Value> get(const Key& key, const Make& make)
  {
    {
      std::lock_guard<std::mutex> lock(this->Mutex);
      for (auto e = this->Entries.begin(); e != this->Entries.end(); ++e)
        if (e->first == key)
        {
          this->Entries.splice(this->Entries.begin(), this->Entries, e);
          return this->Entries.front().second;
        }
    }
    auto made = std::make_shared<const Value>(make());
    std::lock_guard<std::mutex> lock(this->Mutex);
    ++this->Made;
    this->Entries.emplace_front(key, made);
    while (this->Entries.size() > this->Capacity)
      this->Entries.pop_back();
    return made;
  }

  /// How many results `get` made (rather than found kept) so far.
  std::size_t made() const
  {
    std::lock_guard<std::mutex> lock(this->Mutex);
    return this->Made;
  }

private:
  mutable std::mutex Mutex;
  std::list<std::pair<Key, std::shared_ptr<const Value>>> Entries; ///< most recently used first
  std::size_t Capacity, Made = 0;
};
}

#endif
