// Embree 3 on the rays `chambre bench rays --write-rays DIR` writes: the same mesh, the same
// coherent camera rays and incoherent rays, closest hit and any hit, one ray at a time
// (rtcIntersect1 / rtcOccluded1) and in packets of 16 (rtcIntersect16 / rtcOccluded16; the camera's
// also with RTC_INTERSECT_CONTEXT_FLAG_COHERENT), timed
// as chambre times its own: all cores, one untimed run for the checksum, a warm-up of at least
// 300 ms, then `--runs` timed runs; Mrays/s median (the upper of an even count), min and max.
//
// Packets of 16: the camera's rays as tiles of 4x4 pixels of a frame (tiles cut short at the
// image's edges leave lanes invalid), the incoherent rays sixteen consecutive ones.
// Threads take blocks of 1024 rays (64 packets) from a shared counter, as rayon's pool takes
// chambre's (`with_min_len(1024)`).
//
// Usage: bench_embree DIR [--runs N] [--threads N] [--json FILE]
// Prints a Markdown table; --json writes the same figures as JSON.

#include <embree3/rtcore.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace {

[[noreturn]] void fail(const std::string& message) {
  std::fprintf(stderr, "bench_embree: %s\n", message.c_str());
  std::exit(1);
}

std::map<std::string, double> read_header(const std::string& path) {
  std::ifstream in(path);
  if (!in) fail(path + ": cannot read");
  std::map<std::string, double> header;
  std::string key;
  double value;
  int line = 0;
  std::string text;
  while (std::getline(in, text)) {
    ++line;
    std::istringstream fields(text);
    if (!(fields >> key >> value)) fail(path + ":" + std::to_string(line) + ": not `key value`");
    header[key] = value;
  }
  return header;
}

double field(const std::map<std::string, double>& header, const std::string& key) {
  auto it = header.find(key);
  if (it == header.end()) fail("rays.txt: no `" + key + "`");
  return it->second;
}

// A file of `count` little-endian 32-bit words (this program runs on little-endian x86).
template <typename T>
std::vector<T> read_words(const std::string& path, size_t count) {
  static_assert(sizeof(T) == 4, "32-bit words");
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) fail(path + ": cannot read");
  size_t bytes = static_cast<size_t>(in.tellg());
  if (bytes != 4 * count)
    fail(path + ": " + std::to_string(bytes) + " bytes, expected " + std::to_string(4 * count));
  std::vector<T> words(count);
  in.seekg(0);
  in.read(reinterpret_cast<char*>(words.data()), static_cast<std::streamsize>(bytes));
  return words;
}

struct Rays {
  const char* name = "";
  std::vector<float> data;  // origin x y z, direction x y z per ray
  size_t count = 0;
  // The camera's rays: packets are 4x4 pixel tiles of frames `width` x `height`.
  uint32_t width = 0, height = 0;
  // Per packet, its rays (UINT32_MAX: an invalid lane).
  std::vector<uint32_t> packets;
};

constexpr uint32_t kNoRay = UINT32_MAX;
constexpr size_t kBlock = 1024;

void group_packets(Rays& rays) {
  if (rays.width == 0) {
    for (size_t i = 0; i < rays.count; i += 16)
      for (size_t k = 0; k < 16; ++k)
        rays.packets.push_back(i + k < rays.count ? static_cast<uint32_t>(i + k) : kNoRay);
    return;
  }
  size_t frame = size_t(rays.width) * rays.height;
  for (size_t f = 0; f * frame < rays.count; ++f)
    for (uint32_t ty = 0; ty < rays.height; ty += 4)
      for (uint32_t tx = 0; tx < rays.width; tx += 4)
        for (uint32_t y = ty; y < ty + 4; ++y)
          for (uint32_t x = tx; x < tx + 4; ++x)
            rays.packets.push_back(x < rays.width && y < rays.height
                                       ? static_cast<uint32_t>(f * frame + y * rays.width + x)
                                       : kNoRay);
}

// Runs `work(begin, end)` over [0, items) in blocks of `block` on `threads` threads.
void parallel(size_t items, size_t block, unsigned threads,
              const std::function<void(size_t, size_t)>& work) {
  std::atomic<size_t> next{0};
  auto worker = [&] {
    for (;;) {
      size_t begin = next.fetch_add(block);
      if (begin >= items) return;
      work(begin, std::min(items, begin + block));
    }
  };
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
}

enum class Query { Closest, Any };

struct Tracer {
  RTCScene scene;
  unsigned threads;
  float t_far;

  void one_ray(const Rays& rays, Query query, RTCIntersectContextFlags flags,
               std::vector<float>& out) const {
    parallel(rays.count, kBlock, threads, [&](size_t begin, size_t end) {
      RTCIntersectContext context;
      rtcInitIntersectContext(&context);
      context.flags = flags;
      for (size_t i = begin; i < end; ++i) {
        const float* r = &rays.data[6 * i];
        RTCRayHit rh;
        rh.ray.org_x = r[0], rh.ray.org_y = r[1], rh.ray.org_z = r[2];
        rh.ray.dir_x = r[3], rh.ray.dir_y = r[4], rh.ray.dir_z = r[5];
        rh.ray.tnear = 0.0f;
        rh.ray.tfar = t_far;
        rh.ray.time = 0.0f;
        rh.ray.mask = UINT32_MAX;
        rh.ray.id = 0;
        rh.ray.flags = 0;
        if (query == Query::Closest) {
          rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
          rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
          rtcIntersect1(scene, &context, &rh);
          out[i] = rh.hit.geomID != RTC_INVALID_GEOMETRY_ID ? rh.ray.tfar : t_far;
        } else {
          rtcOccluded1(scene, &context, &rh.ray);
          out[i] = rh.ray.tfar < 0.0f ? 0.0f : t_far;
        }
      }
    });
  }

  void packets16(const Rays& rays, Query query, RTCIntersectContextFlags flags,
                 std::vector<float>& out) const {
    size_t packets = rays.packets.size() / 16;
    parallel(packets, kBlock / 16, threads, [&](size_t begin, size_t end) {
      RTCIntersectContext context;
      rtcInitIntersectContext(&context);
      context.flags = flags;
      alignas(64) RTCRayHit16 rh;
      alignas(64) int valid[16];
      for (size_t p = begin; p < end; ++p) {
        const uint32_t* lanes = &rays.packets[16 * p];
        for (int k = 0; k < 16; ++k) {
          uint32_t i = lanes[k];
          valid[k] = i == kNoRay ? 0 : -1;
          const float* r = &rays.data[6 * size_t(i == kNoRay ? 0 : i)];
          rh.ray.org_x[k] = r[0], rh.ray.org_y[k] = r[1], rh.ray.org_z[k] = r[2];
          rh.ray.dir_x[k] = r[3], rh.ray.dir_y[k] = r[4], rh.ray.dir_z[k] = r[5];
          rh.ray.tnear[k] = 0.0f;
          rh.ray.tfar[k] = t_far;
          rh.ray.time[k] = 0.0f;
          rh.ray.mask[k] = UINT32_MAX;
          rh.ray.id[k] = k;
          rh.ray.flags[k] = 0;
          rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
          rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
        }
        if (query == Query::Closest) {
          rtcIntersect16(valid, scene, &context, &rh);
          for (int k = 0; k < 16; ++k)
            if (lanes[k] != kNoRay)
              out[lanes[k]] = rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID ? rh.ray.tfar[k] : t_far;
        } else {
          rtcOccluded16(valid, scene, &context, &rh.ray);
          for (int k = 0; k < 16; ++k)
            if (lanes[k] != kNoRay) out[lanes[k]] = rh.ray.tfar[k] < 0.0f ? 0.0f : t_far;
        }
      }
    });
  }
};

struct Spread {
  double median, min, max;
};

Spread spread_of(std::vector<double> samples) {
  std::sort(samples.begin(), samples.end());
  return {samples[samples.size() / 2], samples.front(), samples.back()};
}

struct Result {
  std::string set, query, api;
  size_t rays;
  Spread mrays;
  uint64_t hits;
  double sum_t;
};

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) fail("usage: bench_embree DIR [--runs N] [--threads N] [--json FILE]");
  std::string dir = argv[1];
  unsigned runs = 5, threads = std::max(1u, std::thread::hardware_concurrency());
  std::string json;
  for (int a = 2; a < argc; ++a) {
    std::string arg = argv[a];
    if (a + 1 >= argc) fail(arg + ": needs a value");
    std::string value = argv[++a];
    if (arg == "--runs") runs = std::max(1, std::atoi(value.c_str()));
    else if (arg == "--threads") threads = std::max(1, std::atoi(value.c_str()));
    else if (arg == "--json") json = value;
    else fail(arg + ": unknown option");
  }

  auto header = read_header(dir + "/rays.txt");
  size_t triangles = size_t(field(header, "triangles"));
  size_t vertex_count = size_t(field(header, "vertices"));
  float t_far = float(field(header, "t_far"));
  auto vertices = read_words<float>(dir + "/vertices.f32", 3 * vertex_count);
  auto indices = read_words<uint32_t>(dir + "/indices.u32", 3 * triangles);
  for (uint32_t i : indices)
    if (i >= vertex_count) fail("indices.u32: index " + std::to_string(i) + " out of range");

  Rays coherent, incoherent;
  coherent.name = "coherent";
  incoherent.name = "incoherent";
  coherent.count = size_t(field(header, "coherent_rays"));
  coherent.width = uint32_t(field(header, "width"));
  coherent.height = uint32_t(field(header, "height"));
  coherent.data = read_words<float>(dir + "/coherent.f32", 6 * coherent.count);
  incoherent.count = size_t(field(header, "incoherent_rays"));
  incoherent.data = read_words<float>(dir + "/incoherent.f32", 6 * incoherent.count);
  group_packets(coherent);
  group_packets(incoherent);

  RTCDevice device = rtcNewDevice(nullptr);
  if (!device) fail("rtcNewDevice failed");
  // Without native 16-wide packets (an ISA below AVX-512), Embree traces rtcIntersect16's
  // rays in narrower packets; the report says which.
  bool native16 = rtcGetDeviceProperty(device, RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED) != 0;

  // Embree's defaults: RTC_BUILD_QUALITY_MEDIUM, no scene flags (not RTC_SCENE_FLAG_ROBUST).
  auto build_start = std::chrono::steady_clock::now();
  RTCScene scene = rtcNewScene(device);
  rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_MEDIUM);
  RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  rtcSetGeometryBuildQuality(geometry, RTC_BUILD_QUALITY_MEDIUM);
  float* v = static_cast<float*>(rtcSetNewGeometryBuffer(
      geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), vertex_count));
  std::memcpy(v, vertices.data(), vertices.size() * sizeof(float));
  uint32_t* idx = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(
      geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), triangles));
  std::memcpy(idx, indices.data(), indices.size() * sizeof(uint32_t));
  rtcCommitGeometry(geometry);
  rtcAttachGeometry(scene, geometry);
  rtcReleaseGeometry(geometry);
  rtcCommitScene(scene);
  double build_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - build_start)
          .count();
  if (rtcGetDeviceError(device) != RTC_ERROR_NONE) fail("Embree reported an error building");

  Tracer tracer{scene, threads, t_far};
  std::vector<Result> results;
  // Each ray set through each API: one ray at a time and packets of 16 with the context's
  // default flags (rtcInitIntersectContext's: incoherent), and the camera's packets also with
  // RTC_INTERSECT_CONTEXT_FLAG_COHERENT, under which Embree traverses a packet's frustum.
  struct Mode {
    const char* api;
    bool packets;
    RTCIntersectContextFlags flags;
    bool camera_only;
  };
  const Mode modes[] = {
      {"one ray", false, RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT, false},
      {"packets of 16", true, RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT, false},
      {"packets of 16, coherent flag", true, RTC_INTERSECT_CONTEXT_FLAG_COHERENT, true},
  };
  for (Rays* rays : {&coherent, &incoherent}) {
    for (Query query : {Query::Closest, Query::Any}) {
      for (const Mode& mode : modes) {
        if (mode.camera_only && rays->width == 0) continue;
        std::vector<float> out(rays->count, t_far);
        auto trace = [&] {
          auto start = std::chrono::steady_clock::now();
          if (mode.packets) tracer.packets16(*rays, query, mode.flags, out);
          else tracer.one_ray(*rays, query, mode.flags, out);
          return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        };
        trace();
        Result r{rays->name, query == Query::Closest ? "closest" : "any", mode.api,
                 rays->count, {}, 0, 0.0};
        for (float t : out)
          if (t < t_far) r.hits += 1, r.sum_t += t;
        auto warm_up = std::chrono::steady_clock::now();
        while (std::chrono::duration<double>(std::chrono::steady_clock::now() - warm_up).count() < 0.3)
          trace();
        std::vector<double> mrays;
        for (unsigned i = 0; i < runs; ++i) mrays.push_back(double(rays->count) / trace() / 1e6);
        r.mrays = spread_of(mrays);
        results.push_back(r);
      }
    }
  }
  if (rtcGetDeviceError(device) != RTC_ERROR_NONE) fail("Embree reported an error tracing");

  std::printf(
      "Embree %s: %zu triangles (BVH built in %.0f ms, medium quality), %u threads, 16-wide "
      "packets %s; median of %u runs after a warm-up\n\n",
      RTC_VERSION_STRING, triangles, build_ms, threads,
      native16 ? "native" : "emulated (not native on this CPU)", runs);
  std::printf("| rays | query | Embree | Mrays/s median | min | max | hits | sum of t |\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  for (auto& r : results)
    std::printf("| %s | %s | %s | %.2f | %.2f | %.2f | %llu | %.6e |\n", r.set.c_str(),
                r.query.c_str(), r.api.c_str(), r.mrays.median, r.mrays.min, r.mrays.max,
                static_cast<unsigned long long>(r.hits), r.sum_t);
  if (!json.empty()) {
    std::ofstream out(json + ".tmp");
    out << "{\"embree\": \"" << RTC_VERSION_STRING << "\", \"threads\": " << threads
        << ", \"native_ray16\": " << (native16 ? "true" : "false") << ", \"build_ms\": " << build_ms
        << ", \"runs\": " << runs << ", \"results\": [";
    for (size_t i = 0; i < results.size(); ++i) {
      auto& r = results[i];
      char line[512];
      std::snprintf(line, sizeof line,
                    "%s{\"set\": \"%s\", \"query\": \"%s\", \"api\": \"%s\", \"rays\": %zu, "
                    "\"median\": %.4f, \"min\": %.4f, \"max\": %.4f, \"hits\": %llu, "
                    "\"sum_t\": %.9e}",
                    i ? ", " : "", r.set.c_str(), r.query.c_str(), r.api.c_str(), r.rays,
                    r.mrays.median, r.mrays.min, r.mrays.max,
                    static_cast<unsigned long long>(r.hits), r.sum_t);
      out << line;
    }
    out << "]}\n";
    out.close();
    if (!out || std::rename((json + ".tmp").c_str(), json.c_str()) != 0)
      fail(json + ": cannot write");
  }
  rtcReleaseScene(scene);
  rtcReleaseDevice(device);
  return 0;
}
