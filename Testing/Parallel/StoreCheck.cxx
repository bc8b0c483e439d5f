// What the MPI test scripts ask of a database, through the store's API (and plain SQL for what
// the API deliberately hides: the tiles of a frame nobody can see).
//
// Usage: asrtStoreCheck COMMAND ...
//   createdb NAME            creates database NAME next to $ASRT_TEST_CONNINFO's, prints its
//                            conninfo
//   frames CONNINFO          the complete frames (listFrames): "N complete: ID ..."
//   abandoned CONNINFO       frames still being written (abandonedFrames(0 s)): "ID ..."
//   tiles CONNINFO ID        "WRITTEN/TOTAL" tiles of frame ID, complete or not
//   visible-rays CONNINFO ID rays of frame ID that SQL sees in rays_v
//   delete CONNINFO ID       deleteFrame(ID)
//   same CONNINFO_A CONNINFO_B
//                            the only complete frame of each database holds the same records
//                            in the same order, bit for bit; exit 1 naming the first difference
#include "RayStore.h"
#include "StoreTestSupport.h"

#include <cstdio>
#include <cstdlib>
#include <string>

using asrt::RayStore;
using asrt::testing::Db;

namespace
{
int usage()
{
  std::fprintf(stderr, "usage: asrtStoreCheck createdb NAME | frames CI | abandoned CI | tiles CI "
                       "ID | visible-rays CI ID | delete CI ID | same CI_A CI_B\n");
  return 2;
}

std::int64_t onlyFrame(RayStore& store, const char* which)
{
  const std::vector<asrt::FrameInfo> frames = store.listFrames();
  if (frames.size() != 1)
    throw std::runtime_error(std::string(which) + " holds " + std::to_string(frames.size()) +
                             " complete frames, not 1");
  return frames[0].id;
}
}

int main(int argc, char* argv[])
{
  if (argc < 3)
    return usage();
  const std::string command = argv[1];
  try
  {
    if (command == "createdb")
    {
      const char* base = std::getenv("ASRT_TEST_CONNINFO");
      if (!base)
        throw std::runtime_error("ASRT_TEST_CONNINFO is not set");
      const std::string name = argv[2];
      Db(base).value("CREATE DATABASE \"" + name + "\"");
      std::string conninfo = base;
      const std::size_t at = conninfo.find("dbname=");
      const std::size_t end = conninfo.find(' ', at);
      conninfo.replace(at, end == std::string::npos ? std::string::npos : end - at,
                       "dbname=" + name);
      std::printf("%s\n", conninfo.c_str());
      return 0;
    }
    RayStore store(argv[2]);
    if (command == "frames")
    {
      const std::vector<asrt::FrameInfo> frames = store.listFrames();
      std::printf("%zu complete:", frames.size());
      for (const asrt::FrameInfo& f : frames)
        std::printf(" %lld", static_cast<long long>(f.id));
      std::printf("\n");
      return 0;
    }
    if (command == "abandoned")
    {
      for (std::int64_t id : store.abandonedFrames(std::chrono::seconds(0)))
        std::printf("%lld ", static_cast<long long>(id));
      std::printf("\n");
      return 0;
    }
    if (argc < 4)
      return usage();
    if (command == "tiles")
    {
      Db db(argv[2]);
      const std::string id = std::to_string(std::stoll(argv[3]));
      std::printf("%s/%s\n",
                  db.value("SELECT count(*) FROM frame_tiles WHERE frame_id = " + id).c_str(),
                  db.value("SELECT tile_count FROM frames WHERE id = " + id).c_str());
      return 0;
    }
    if (command == "visible-rays")
    {
      Db db(argv[2]);
      const std::string id = std::to_string(std::stoll(argv[3]));
      std::printf("%s\n", db.value("SELECT count(*) FROM rays_v WHERE frame_id = " + id).c_str());
      return 0;
    }
    if (command == "delete")
    {
      store.deleteFrame(std::stoll(argv[3]));
      return 0;
    }
    if (command == "same")
    {
      RayStore other(argv[3]);
      const std::vector<asrt::RayRecord> a = store.readFrame(onlyFrame(store, "the first"));
      const std::vector<asrt::RayRecord> b = other.readFrame(onlyFrame(other, "the second"));
      if (a.size() != b.size())
      {
        std::printf("different sizes: %zu and %zu records\n", a.size(), b.size());
        return 1;
      }
      for (std::size_t k = 0; k < a.size(); ++k)
        if (asrt::testing::recordBits(a[k]) != asrt::testing::recordBits(b[k]))
        {
          std::printf("record %zu differs: pixel (%d, %d) and (%d, %d)\n", k, a[k].i, a[k].j,
                      b[k].i, b[k].j);
          return 1;
        }
      std::printf("%zu records identical, bit for bit, in the same order\n", a.size());
      return 0;
    }
    return usage();
  }
  catch (const std::exception& e)
  {
    std::fprintf(stderr, "asrtStoreCheck %s: %s\n", command.c_str(), e.what());
    return 1;
  }
}
