// Accumulation in PostgreSQL (issue 4): writes and reads a 200×200 and a 1920×1080 frame of ray
// records through RayStore on a private durable server (fsync on), the same 1920×1080 records
// through a raw binary file with fflush + fsync on the same disk, and the predicate read
// "object_id = 2 AND image_order = 1". Prints a Markdown section for bench/REPORT.md.
//
// The records are synthetic (nothing is traced): deterministic pseudo-random but plausible values
// (a shadow, a photon ring with image orders 1 and 2, three objects, escaped rays, NaN Jacobians
// along edges), so that only storage is measured.
//
// Usage: asrt_bench_store [scratch-directory]
//   The server's cluster and the file go into a fresh directory made under scratch-directory
//   (default: the build directory holding bin/asrt_bench_store); it is removed at the end.
#include "EmbeddedPostgres.h"
#include "RayStore.h"

#include <fcntl.h>
#include <pwd.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

using namespace asrt;

namespace
{
constexpr double Pi = 3.14159265358979323846;
constexpr int Repetitions = 3; // best of three: the machine is shared
const char* const Predicate = "object_id = 2 AND image_order = 1";

double now()
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

std::uint64_t splitmix(std::uint64_t& s)
{
  std::uint64_t z = (s += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

/// Uniform in [0, 1).
double uniform(std::uint64_t& s)
{
  return double(splitmix(s) >> 11) * 0x1.0p-53;
}

/// A frame of plausible records, row-major from the bottom-left: a camera at r = 30 looking at the
/// hole, a shadow of radius 5.2 M (captured rays), a photon ring just outside it (image orders 1
/// and 2), three objects (ids 0–2) hit by 60 % of the other rays, and the rest escaped.
std::vector<RayRecord> plausibleFrame(int width, int height)
{
  std::vector<RayRecord> out(std::size_t(width) * std::size_t(height));
  const double fov = 40 * Pi / 180, scale = std::tan(fov / 2) / (height / 2.0);
  const double rCam = 30, lapse = std::sqrt(1 - 2 / rCam);
  for (int j = 0; j < height; ++j)
  {
    for (int i = 0; i < width; ++i)
    {
      const std::size_t k = std::size_t(j) * std::size_t(width) + std::size_t(i);
      std::uint64_t s = 0x5EED0000ull + k;
      RayRecord& r = out[k];
      r.i = i;
      r.j = j;
      r.origin = Vec3(rCam, 0, 0);
      r.direction =
        Vec3((i + 0.5 - width / 2.0) * scale, (j + 0.5 - height / 2.0) * scale, 1).normalized();
      const Vec3& d = r.direction;
      r.momentum = Vec4(-1, -d.z() / lapse, d.x() / lapse, d.y() / lapse);
      const double b = rCam * std::sqrt(1 - d.z() * d.z()); // impact parameter (flat estimate)
      const double angle = std::atan2(d.y(), d.x());
      r.steps = 150 + std::int64_t(splitmix(s) % 400);
      r.maxAbsH = uniform(s) * 1e-10;
      r.chordError = uniform(s) * 1e-9;
      if (b < 5.2)
      {
        r.termination = Termination::Captured;
        r.objectId = -1;
        r.imageOrder = 0;
        const double th = uniform(s) * Pi, ph = uniform(s) * 2 * Pi;
        r.hitPoint =
          2.0001 * Vec3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
        r.winding = angle + uniform(s);
        r.affineLength = rCam - 2 + uniform(s) * 5;
        r.color = Vec3::Zero();
      }
      else
      {
        const double ring = b - 5.2;
        r.imageOrder = ring < 0.05 ? 2 : ring < 0.6 ? 1 : 0;
        r.steps += std::int64_t(2000 / (ring + 0.5));
        r.winding = r.imageOrder * Pi + uniform(s) * Pi;
        if (uniform(s) < 0.6)
        {
          r.termination = Termination::HitObject;
          r.objectId = int(splitmix(s) % 3);
          const double rad = 6 + 4 * r.objectId + uniform(s);
          const double ph = angle + uniform(s) * 0.1;
          r.hitPoint = Vec3(rad * std::cos(ph), rad * std::sin(ph), uniform(s) * 4 - 2);
          r.hitNormal = Vec3(std::cos(ph), std::sin(ph), 0);
          r.u = std::fmod(ph / (2 * Pi) + 1, 1);
          r.v = uniform(s);
          r.affineLength = rCam + rad + uniform(s) * 10;
          r.color = Vec3(uniform(s), uniform(s), uniform(s));
        }
        else
        {
          r.termination = Termination::Escaped;
          r.objectId = -1;
          const double th = std::acos(d.y()), ph = angle + r.winding;
          r.hitPoint =
            1000 * Vec3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
          r.u = std::fmod(ph / (2 * Pi) + 10, 1);
          r.v = th / Pi;
          r.affineLength = 1000 + uniform(s) * 50;
          r.color = Vec3(0.1 * uniform(s), 0.1 * uniform(s), 0.2 * uniform(s));
        }
      }
      // Jacobians: NaN where no neighbour hit the same thing (about 4 % of pixels, the edges).
      if (r.objectId < 0 || uniform(s) < 0.04)
      {
        r.dudi = r.dudj = r.dvdi = r.dvdj = std::numeric_limits<double>::quiet_NaN();
      }
      else
      {
        r.dudi = (uniform(s) - 0.5) * 1e-2;
        r.dudj = (uniform(s) - 0.5) * 1e-3;
        r.dvdi = (uniform(s) - 0.5) * 1e-3;
        r.dvdj = (uniform(s) - 0.5) * 1e-2;
      }
    }
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// The raw file: the same fields the store sends (5 int32, 1 int64 and 29 float64 words, 260
// bytes per record), packed in native byte order.

constexpr std::size_t RecordBytes = 5 * 4 + 8 + 29 * 8;

template<class T>
char* put(char* p, T v)
{
  std::memcpy(p, &v, sizeof(T));
  return p + sizeof(T);
}
template<class T>
const char* get(const char* p, T& v)
{
  std::memcpy(&v, p, sizeof(T));
  return p + sizeof(T);
}

void pack(const RayRecord& r, char* p)
{
  p = put(p, r.i);
  p = put(p, r.j);
  for (int c = 0; c < 3; ++c)
    p = put(p, r.origin[c]);
  for (int c = 0; c < 3; ++c)
    p = put(p, r.direction[c]);
  for (int c = 0; c < 4; ++c)
    p = put(p, r.momentum[c]);
  p = put(p, std::int32_t(r.termination));
  p = put(p, r.objectId);
  for (int c = 0; c < 3; ++c)
    p = put(p, r.hitPoint[c]);
  for (int c = 0; c < 3; ++c)
    p = put(p, r.hitNormal[c]);
  for (double v : { r.u, r.v, r.chordError, r.affineLength, r.winding })
    p = put(p, v);
  p = put(p, r.imageOrder);
  p = put(p, r.steps);
  p = put(p, r.maxAbsH);
  for (int c = 0; c < 3; ++c)
    p = put(p, r.color[c]);
  for (double v : { r.dudi, r.dudj, r.dvdi, r.dvdj })
    p = put(p, v);
}

void unpack(const char* p, RayRecord& r)
{
  p = get(p, r.i);
  p = get(p, r.j);
  for (int c = 0; c < 3; ++c)
    p = get(p, r.origin[c]);
  for (int c = 0; c < 3; ++c)
    p = get(p, r.direction[c]);
  for (int c = 0; c < 4; ++c)
    p = get(p, r.momentum[c]);
  std::int32_t t;
  p = get(p, t);
  r.termination = Termination(t);
  p = get(p, r.objectId);
  for (int c = 0; c < 3; ++c)
    p = get(p, r.hitPoint[c]);
  for (int c = 0; c < 3; ++c)
    p = get(p, r.hitNormal[c]);
  for (double* v : { &r.u, &r.v, &r.chordError, &r.affineLength, &r.winding })
    p = get(p, *v);
  p = get(p, r.imageOrder);
  p = get(p, r.steps);
  p = get(p, r.maxAbsH);
  for (int c = 0; c < 3; ++c)
    p = get(p, r.color[c]);
  for (double* v : { &r.dudi, &r.dudj, &r.dvdi, &r.dvdj })
    p = get(p, *v);
}

constexpr std::size_t ChunkRecords = 4096;

void writeFile(const std::string& path, const std::vector<RayRecord>& records)
{
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f)
    throw std::runtime_error("cannot create " + path + ": " + std::strerror(errno));
  std::vector<char> buf(ChunkRecords * RecordBytes);
  for (std::size_t first = 0; first < records.size(); first += ChunkRecords)
  {
    const std::size_t n = std::min(ChunkRecords, records.size() - first);
    for (std::size_t k = 0; k < n; ++k)
      pack(records[first + k], buf.data() + k * RecordBytes);
    if (std::fwrite(buf.data(), RecordBytes, n, f) != n)
      throw std::runtime_error("writing " + path + " failed");
  }
  if (std::fflush(f) != 0 || fsync(fileno(f)) != 0 || std::fclose(f) != 0)
    throw std::runtime_error("flushing " + path + " failed: " + std::strerror(errno));
}

std::vector<RayRecord> readFile(const std::string& path)
{
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f)
    throw std::runtime_error("cannot open " + path + ": " + std::strerror(errno));
  std::fseek(f, 0, SEEK_END);
  const std::size_t count = std::size_t(std::ftell(f)) / RecordBytes;
  std::fseek(f, 0, SEEK_SET);
  std::vector<RayRecord> out(count);
  std::vector<char> buf(ChunkRecords * RecordBytes);
  for (std::size_t first = 0; first < count; first += ChunkRecords)
  {
    const std::size_t n = std::min(ChunkRecords, count - first);
    if (std::fread(buf.data(), RecordBytes, n, f) != n)
      throw std::runtime_error("reading " + path + " failed");
    for (std::size_t k = 0; k < n; ++k)
      unpack(buf.data() + k * RecordBytes, out[first + k]);
  }
  std::fclose(f);
  return out;
}

/// Drops the file's pages from the page cache (they are clean after the fsync).
void dropCache(const std::string& path)
{
  const int fd = open(path.c_str(), O_RDONLY);
  if (fd < 0 || posix_fadvise(fd, 0, 0, POSIX_FADV_DONTNEED) != 0)
    throw std::runtime_error("cannot drop the page cache of " + path);
  close(fd);
}

/// Bit-exact comparison through the packed form.
bool sameBits(const std::vector<RayRecord>& a, const std::vector<RayRecord>& b)
{
  if (a.size() != b.size())
    return false;
  char x[RecordBytes], y[RecordBytes];
  for (std::size_t k = 0; k < a.size(); ++k)
  {
    pack(a[k], x);
    pack(b[k], y);
    if (std::memcmp(x, y, RecordBytes) != 0)
      return false;
  }
  return true;
}

// ---------------------------------------------------------------------------------------------

struct Timing
{
  double write = 1e300, read = 1e300, predicate = 1e300;
  std::size_t selected = 0;
};

SceneDescription frameScene(int width, int height, double mass)
{
  SceneDescription d;
  d.name = "storage benchmark (synthetic records)";
  d.mass = mass;
  d.camera.width = width;
  d.camera.height = height;
  return d;
}

Timing measureStore(RayStore& store, const std::vector<RayRecord>& records, int width, int height,
                    bool predicate, double& mass)
{
  Timing t;
  for (int rep = 0; rep < Repetitions; ++rep)
  {
    double t0 = now();
    const std::int64_t id =
      store.writeFrame(frameScene(width, height, mass += 1), "bench", records);
    t.write = std::min(t.write, now() - t0);
    {
      t0 = now();
      const std::vector<RayRecord> back = store.readFrame(id);
      t.read = std::min(t.read, now() - t0);
      if (rep == 0 && !sameBits(back, records))
        throw std::runtime_error("the store did not give the records back bit-exact");
    }
    if (predicate)
    {
      t0 = now();
      const std::vector<RayRecord> some = store.readFrame(id, Predicate);
      t.predicate = std::min(t.predicate, now() - t0);
      t.selected = some.size();
    }
    store.deleteFrame(id);
  }
  return t;
}

std::string makeScratch(const std::string& parent)
{
  std::string tmpl = parent + "/pgbench-XXXXXX";
  if (!mkdtemp(tmpl.data()))
    throw std::runtime_error("mkdtemp " + tmpl + ": " + std::strerror(errno));
  if (geteuid() == 0)
  {
    // mkdtemp's directory is root's and private; the server (user postgres) must get through it.
    if (const passwd* pw = getpwnam("postgres"))
    {
      if (chown(tmpl.c_str(), pw->pw_uid, pw->pw_gid) != 0)
        throw std::runtime_error("chown " + tmpl + ": " + std::strerror(errno));
    }
  }
  return tmpl;
}

/// "ext4 on /dev/vda" for the filesystem holding path (longest mount point prefix).
std::string diskOf(const std::string& path)
{
  std::ifstream mounts("/proc/mounts");
  std::string dev, mnt, type, rest, best, what = "unknown";
  const std::string canon = std::filesystem::canonical(path).string();
  while (mounts >> dev >> mnt >> type && std::getline(mounts, rest))
  {
    const bool under = canon.compare(0, mnt.size(), mnt) == 0 &&
                       (mnt == "/" || canon.size() == mnt.size() || canon[mnt.size()] == '/');
    if (under && mnt.size() >= best.size())
    {
      best = mnt;
      what = type + " on " + dev;
    }
  }
  return what;
}

std::string rate(std::size_t rays, double seconds)
{
  char s[64];
  std::snprintf(s, sizeof s, "%.2f M", double(rays) / seconds / 1e6);
  return s;
}
}

int main(int argc, char* argv[])
{
  std::string parent;
  if (argc > 1)
    parent = argv[1];
  else
    parent = std::filesystem::canonical("/proc/self/exe").parent_path().parent_path().string();

  std::string scratch;
  try
  {
    scratch = makeScratch(parent);
  }
  catch (const std::exception& e)
  {
    std::fprintf(stderr, "asrt_bench_store: %s\n", e.what());
    return 1;
  }
  EmbeddedPostgres server(scratch + "/data");
  server.setDurable(true); // the default, said out loud: fsync on, like the file below
  int status = 0;
  try
  {
    const double tStart = now();
    const std::string conninfo = server.ensureRunning();
    RayStore store(conninfo);
    store.migrate();
    double mass = 1;

    const std::vector<RayRecord> small = plausibleFrame(200, 200);
    const Timing s = measureStore(store, small, 200, 200, false, mass);

    const std::vector<RayRecord> hd = plausibleFrame(1920, 1080);
    const Timing h = measureStore(store, hd, 1920, 1080, true, mass);

    const std::string file = scratch + "/frame.bin";
    Timing f;
    double coldRead = 1e300;
    for (int rep = 0; rep < Repetitions; ++rep)
    {
      double t0 = now();
      writeFile(file, hd);
      f.write = std::min(f.write, now() - t0);
      t0 = now();
      {
        const std::vector<RayRecord> back = readFile(file);
        f.read = std::min(f.read, now() - t0);
        if (rep == 0 && !sameBits(back, hd))
          throw std::runtime_error("the file did not give the records back bit-exact");
      }
      dropCache(file);
      t0 = now();
      const std::vector<RayRecord> cold = readFile(file);
      coldRead = std::min(coldRead, now() - t0);
      std::filesystem::remove(file);
    }
    const double total = now() - tStart;

    const std::size_t nS = small.size(), nH = hd.size();
    const double writeRatio = h.write / f.write, readRatio = h.read / f.read;
    std::printf("<!-- store:begin -->\n## Accumulation in PostgreSQL\n\n");
    std::printf(
      "RayStore (binary COPY of %d-ray blocks, one transaction per frame) against a private "
      "PostgreSQL 15 server started for the run with `EmbeddedPostgres`, **durable (fsync on, the "
      "default)**, on this machine: %u cores, the cluster and the file on the same disk (%s). "
      "The records are synthetic — nothing is traced — but plausible: a shadow, a photon ring "
      "with image orders 1 and 2, three objects, escaped rays, NaN Jacobians along edges; "
      "deterministic pseudo-random values, %zu bytes of fields per ray. Times are wall-clock, "
      "best of %d; a write is one `writeFrame` (commit included), a read one `readFrame` into "
      "`RayRecord`s (checked bit-exact once). The file is the same fields packed in native byte "
      "order, one `fwrite` per %zu records, then `fflush` + `fsync`; it is read back with "
      "`fread` and unpacked into `RayRecord`s. Reads of both come from the page cache (the store "
      "and the file were just written); the file read from the disk itself (its pages dropped "
      "with `posix_fadvise`) is shown too.\n\n",
      RayStore::kBlockSize, std::thread::hardware_concurrency(), diskOf(scratch).c_str(),
      RecordBytes, Repetitions, ChunkRecords);
    std::printf("| what | rays | write | write rays/s | read | read rays/s |\n"
                "|---|---|---|---|---|---|\n");
    std::printf("| store, 200×200 | %zu | %.3f s | %s | %.3f s | %s |\n", nS, s.write,
                rate(nS, s.write).c_str(), s.read, rate(nS, s.read).c_str());
    std::printf("| store, 1920×1080 | %zu | %.2f s | %s | %.2f s | %s |\n", nH, h.write,
                rate(nH, h.write).c_str(), h.read, rate(nH, h.read).c_str());
    std::printf("| raw file + fsync, 1920×1080 | %zu | %.2f s | %s | %.2f s | %s |\n", nH, f.write,
                rate(nH, f.write).c_str(), f.read, rate(nH, f.read).c_str());
    std::printf("| raw file, read from disk | %zu | | | %.2f s | %s |\n", nH, coldRead,
                rate(nH, coldRead).c_str());
    std::printf("| store / file | | %.2f× | | %.2f× | |\n", writeRatio, readRatio);
    std::printf("| predicate `%s`, 1920×1080 | %zu selected of %zu | | | %.2f s | %s scanned |\n",
                Predicate, h.selected, nH, h.predicate, rate(nH, h.predicate).c_str());

    const bool fastWrite = nH / h.write >= 1e6, fastRead = nH / h.read >= 1e6;
    const bool nearWrite = writeRatio <= 2, nearRead = readRatio <= 2;
    auto met = [](bool b) { return b ? "**met**" : "**not met**"; };
    std::printf(
      "\nThe paper (SGI Onyx2, 200×200): about 44 min to write a frame to PostgreSQL and 4 min to "
      "read it, files 6× faster than the database. Here the 200×200 frame takes %.3f s to write "
      "and %.3f s to read.\n\n",
      s.write, s.read);
    std::printf("Targets, at 1920×1080:\n\n");
    std::printf("- writing at ≥ 1 M rays/s: %s rays/s, %s;\n", rate(nH, h.write).c_str(),
                met(fastWrite));
    std::printf("- reading at ≥ 1 M rays/s: %s rays/s, %s;\n", rate(nH, h.read).c_str(),
                met(fastRead));
    std::printf("- writing within 2× of the fsync'd file: %.2f×, %s;\n", writeRatio,
                met(nearWrite));
    std::printf("- reading within 2× of the file (both from the page cache): %.2f×, %s.\n",
                readRatio, met(nearRead));
    std::printf("\nThe whole run took %.0f s. Command: `bench/run` (or "
                "`build-bench/bin/asrt_bench_store [scratch-directory]`).\n",
                total);
    std::printf("<!-- store:end -->\n");
  }
  catch (const std::exception& e)
  {
    std::fprintf(stderr, "asrt_bench_store: %s\n", e.what());
    status = 1;
  }
  try
  {
    server.destroy();
  }
  catch (const std::exception& e)
  {
    std::fprintf(stderr, "asrt_bench_store: removing the server failed: %s\n", e.what());
    status = 1;
  }
  std::error_code ec;
  std::filesystem::remove_all(scratch, ec);
  return status;
}
