#include "TraceAndStore.h"

#include <atomic>
#include <condition_variable>
#include <deque>
#include <exception>
#include <mutex>
#include <stdexcept>
#include <thread>

namespace asrt
{
std::int64_t traceAndStore(const FrameTracer& tracer, RayStore& store,
                           const TraceAndStoreOptions& options)
{
  const SceneDescription& d = tracer.description();
  const int W = d.camera.width, H = d.camera.height;
  const int band = std::max(1, options.rowsPerChunk);
  const std::size_t total = static_cast<std::size_t>(W) * H;

  // Bands flow from the tracing thread to the COPY through a small queue: at most two bands wait,
  // so memory stays bounded on large frames while the tracer keeps ahead of the database.
  struct Band
  {
    std::size_t first = 0;
    std::vector<RayRecord> records;
  };
  std::mutex mutex;
  std::condition_variable ready, room;
  std::deque<Band> queue;
  std::exception_ptr traceError;
  std::atomic<bool> cancel{ false };
  bool finished = false;

  std::thread producer(
    [&]
    {
      try
      {
        for (int row = 0; row < H && !cancel; row += band)
        {
          Band b;
          b.first = static_cast<std::size_t>(row) * W;
          b.records = tracer.traceRows(row, std::min(H, row + band));
          std::unique_lock<std::mutex> lock(mutex);
          room.wait(lock, [&] { return queue.size() < 2 || cancel; });
          queue.push_back(std::move(b));
          ready.notify_one();
        }
      }
      catch (...)
      {
        std::lock_guard<std::mutex> lock(mutex);
        traceError = std::current_exception();
      }
      std::lock_guard<std::mutex> lock(mutex);
      finished = true;
      ready.notify_one();
    });

  Band current;
  bool haveCurrent = false;
  auto next = [&](std::size_t index, RayRecord& out)
  {
    if (!haveCurrent || index >= current.first + current.records.size())
    {
      std::unique_lock<std::mutex> lock(mutex);
      ready.wait(lock, [&] { return !queue.empty() || finished; });
      if (queue.empty())
      {
        if (traceError)
          std::rethrow_exception(traceError);
        throw std::runtime_error("tracing stopped before the frame was complete");
      }
      current = std::move(queue.front());
      queue.pop_front();
      haveCurrent = true;
      room.notify_one();
      lock.unlock();
      // Once a band: the fraction stored so far, and the chance to abort.
      if (options.progress &&
          !options.progress(static_cast<double>(index) / static_cast<double>(total)))
        throw std::runtime_error("aborted: nothing was stored");
    }
    out = current.records[index - current.first];
  };

  std::int64_t id = -1;
  try
  {
    id = store.writeFrame(d, options.label, total, next,
                          FrameWriteOptions().replacing(options.replace));
  }
  catch (...)
  {
    {
      std::lock_guard<std::mutex> lock(mutex);
      cancel = true;
      room.notify_all();
    }
    producer.join();
    throw;
  }
  producer.join();
  if (traceError)
    std::rethrow_exception(traceError);
  return id;
}
}
