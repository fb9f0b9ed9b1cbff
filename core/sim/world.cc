#include "core/sim/world.h"

#include <glog/logging.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <mutex>
#include <tuple>

#include "core/sim/random.h"
#include "core/sim/recorded_path.h"

namespace dala::sim {
namespace {

constexpr int kNumTextures = 8;
constexpr double kCameraHeight = 1.5;  // Rover camera above the ground (m).
constexpr double kStreetHalfWidth = 6.0;

// R_b_c: body (x forward, y left, z up) from camera (x right, y down, z forward).
Eigen::Matrix3d RotationBodyCamera() {
  Eigen::Matrix3d R;
  R << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  return R;
}

// Camera pose from a position and yaw (about world z, 0 = looking east), pitch (positive =
// looking down) and roll (about the viewing direction): R_w_c = Rz(yaw) Ry(pitch) Rx(roll) R_b_c.
Pose CameraPose(const Eigen::Vector3d& p_w, double yaw, double pitch, double roll) {
  const Eigen::Matrix3d R_w_b = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                                 Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                                 Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                                    .toRotationMatrix();
  return MakePose(R_w_b * RotationBodyCamera(), p_w);
}

// ---------------------------------------------------------------------------------------------
// The street loop: a rounded rectangle in closed form,
//   p(th) = (1.2 A (cos th - cos 3th / 6), 1.2 B (sin th + sin 3th / 6)),
// flat along the sides, turning at the four corners; counter-clockwise.
constexpr double kLoopA = 38.0, kLoopB = 24.0;

// `scale` shrinks the circuit (the small_loop preset: 0.5).
Eigen::Vector2d LoopPoint(double th, double scale = 1.0) {
  return {scale * 1.2 * kLoopA * (std::cos(th) - std::cos(3 * th) / 6),
          scale * 1.2 * kLoopB * (std::sin(th) + std::sin(3 * th) / 6)};
}
Eigen::Vector2d LoopTangent(double th, double scale = 1.0) {
  return {scale * 1.2 * kLoopA * (-std::sin(th) + std::sin(3 * th) / 2),
          scale * 1.2 * kLoopB * (std::cos(th) + std::cos(3 * th) / 2)};
}
constexpr double kSmallLoopScale = 0.5;

// Ground rover around the loop, once per `period` seconds; `jerk` adds fast wobbles of the
// heading, pitch, roll, height and a lateral offset (the `fast` preset).
class LoopPath : public CameraPath {
 public:
  LoopPath(double period, bool jerk, double scale = 1.0)
      : period_(period), jerk_(jerk), scale_(scale) {}
  Pose T_w_c(double t) const override {
    const double th = 2 * M_PI * t / period_;
    const Eigen::Vector2d p = LoopPoint(th, scale_);
    const Eigen::Vector2d d = LoopTangent(th, scale_);
    double yaw = std::atan2(d.y(), d.x());
    double pitch = 0.05 + 0.01 * std::sin(2 * M_PI * t / 3.1);
    double roll = 0.005 * std::sin(2 * M_PI * t / 2.3);
    double height = kCameraHeight + 0.02 * std::sin(2 * M_PI * t / 1.7);
    double lateral = 0.0;
    if (jerk_) {
      const double f = 2 * M_PI * t;
      yaw += 0.07 * std::sin(1.7 * f) + 0.04 * std::sin(3.1 * f + 1.0);
      pitch += 0.04 * std::sin(2.3 * f + 0.5) + 0.02 * std::sin(4.3 * f);
      roll += 0.05 * std::sin(1.1 * f + 2.0) + 0.02 * std::sin(3.7 * f);
      height += 0.12 * std::sin(2.7 * f);
      lateral = 0.4 * std::sin(0.9 * f + 0.3);
    }
    const Eigen::Vector2d n = Eigen::Vector2d(-d.y(), d.x()).normalized();
    const Eigen::Vector2d xy = p + lateral * n;
    return CameraPose({xy.x(), xy.y(), height}, yaw, pitch, roll);
  }

 private:
  double period_;
  bool jerk_;
  double scale_;
};

// Pure rotation in place (no translation): a full turn of yaw per period, with pitch and roll
// wobbles, at the middle of the loop's north street.
class RotationPath : public CameraPath {
 public:
  explicit RotationPath(double period) : period_(period) {}
  Pose T_w_c(double t) const override {
    const Eigen::Vector2d p = LoopPoint(M_PI / 2);
    const double yaw = M_PI + 2 * M_PI * t / period_;
    const double pitch = 0.05 + 0.06 * std::sin(2 * M_PI * t / 7.0);
    const double roll = 0.04 * std::sin(2 * M_PI * t / 5.0);
    return CameraPose({p.x(), p.y(), kCameraHeight}, yaw, pitch, roll);
  }

 private:
  double period_;
};

// Terrain height for the flight preset (a sum of sinusoids, +-12 m).
double TerrainHeight(double x, double y) {
  return 6.0 * std::sin(x / 37.0 + 1.0) * std::cos(y / 53.0) + 4.0 * std::sin(x / 19.0 + y / 23.0) +
         2.0 * std::cos(x / 11.0 - y / 13.0);
}

// Blimp-like 6-DoF flight: a figure eight (lemniscate of Gerono) 240 m x 120 m, 30-40 m above
// the terrain's mean, heading along the velocity, camera pitched ~40 deg down, with slow roll
// and pitch oscillations.
class FlightPath : public CameraPath {
 public:
  explicit FlightPath(double period) : period_(period) {}
  Pose T_w_c(double t) const override {
    const double w = 2 * M_PI / period_;
    const Eigen::Vector3d p(120.0 * std::sin(w * t), 60.0 * std::sin(2 * w * t),
                            36.0 + 5.0 * std::sin(3 * w * t + 0.4));
    const Eigen::Vector2d v(120.0 * w * std::cos(w * t), 120.0 * w * std::cos(2 * w * t));
    const double yaw = std::atan2(v.y(), v.x()) + 0.05 * std::sin(2 * M_PI * t / 9.0);
    const double pitch = 0.7 + 0.08 * std::sin(2 * M_PI * t / 11.0);
    const double roll = 0.08 * std::sin(2 * M_PI * t / 13.0 + 1.0);
    return CameraPose(p, yaw, pitch, roll);
  }

 private:
  double period_;
};

// A forward drive down a straight street (x from 0 to `length`), weaving +-0.8 m with a 50 m
// period, so the places at x and x + 100 m are seen from the same relative poses.
class CorridorPath : public CameraPath {
 public:
  explicit CorridorPath(double speed) : speed_(speed) {}
  Pose T_w_c(double t) const override {
    const double x = speed_ * t;
    const double k = 2 * M_PI / 50.0;
    const double y = 0.8 * std::sin(k * x);
    const double yaw = std::atan(0.8 * k * std::cos(k * x));
    const double pitch = 0.05 + 0.01 * std::sin(2 * M_PI * t / 3.1);
    return CameraPose({x, y, kCameraHeight}, yaw, pitch, 0.0);
  }

 private:
  double speed_;
};

// ---------------------------------------------------------------------------------------------
// Scene building.
class SceneBuilder {
 public:
  // flat_light: dim the differences of shading between faces (the weak-texture city, where
  // face edges would otherwise hold all the contrast of the image).
  SceneBuilder(Scene* scene, double texels_per_m, bool flat_light = false)
      : scene_(scene), density_(texels_per_m), flat_light_(flat_light) {}

  // A rectangle o + s a + t b with a randomly placed and rotated texture, `density` texels/m.
  void AddQuad(SimRng& rng, const Eigen::Vector3d& o, const Eigen::Vector3d& a,
               const Eigen::Vector3d& b, double shade = 1.0) {
    Surface s;
    s.o_w = o, s.a_w = a, s.b_w = b;
    s.texture = rng.Int(0, kNumTextures - 1);
    const double phi = rng.Uniform(0, 2 * M_PI);
    const Eigen::Vector2d ea(std::cos(phi), std::sin(phi)), eb(-std::sin(phi), std::cos(phi));
    s.uv_o = Eigen::Vector2d(rng.Uniform(0, 1024), rng.Uniform(0, 1024));
    s.uv_a = ea * density_ * a.norm();
    s.uv_b = eb * density_ * b.norm();
    const double albedo = rng.Uniform(0.8, 1.05);
    s.gain = static_cast<float>(flat_light_ ? shade * (0.9 + 0.1 * albedo)
                                            : shade * albedo * Lighting(a.cross(b)));
    scene_->surfaces.push_back(s);
    for (const Eigen::Vector3d& p :
         {o, Eigen::Vector3d(o + a), Eigen::Vector3d(o + a + b), Eigen::Vector3d(o + b)}) {
      scene_->points_w.push_back(p);
    }
  }

  // An axis-aligned-in-yaw box standing on z0: centre (x, y), yaw, size (length along yaw,
  // depth, height); its four walls and roof.
  void AddBox(SimRng& rng, const Eigen::Vector2d& c, double z0, double yaw, double length,
              double depth, double height) {
    const Eigen::Vector3d ex(std::cos(yaw), std::sin(yaw), 0), ey(-std::sin(yaw), std::cos(yaw), 0);
    const Eigen::Vector3d base =
        Eigen::Vector3d(c.x(), c.y(), z0) - ex * length / 2 - ey * depth / 2;
    const Eigen::Vector3d up(0, 0, height);
    const Eigen::Vector3d L = ex * length, D = ey * depth;
    AddQuad(rng, base, L, up);
    AddQuad(rng, base + L, D, up);
    AddQuad(rng, base + L + D, -L, up);
    AddQuad(rng, base + D, -D, up);
    AddQuad(rng, base + up, L, D);
  }

  // Flat ground tiles (z = 0) of `tile` metres over [x0, x1) x [y0, y1); `tile_rng(ix, iy)`
  // gives each tile's random source so a caller can make two regions identical.
  void AddGround(double x0, double x1, double y0, double y1, double tile,
                 const std::function<SimRng(int, int)>& tile_rng) {
    for (int ix = static_cast<int>(std::floor(x0 / tile)); ix * tile < x1; ++ix) {
      for (int iy = static_cast<int>(std::floor(y0 / tile)); iy * tile < y1; ++iy) {
        SimRng rng = tile_rng(ix, iy);
        AddQuad(rng, {ix * tile, iy * tile, 0.0}, {tile, 0, 0}, {0, tile, 0}, 0.95);
      }
    }
  }

  // Terrain z = TerrainHeight(x, y) as triangles on a grid; each `chunk` x `chunk` block gets
  // its own texture, offset and rotation (texel coordinates are affine in the world x, y).
  void AddTerrain(SimRng& rng, double x0, double x1, double y0, double y1, double step,
                  double chunk) {
    const int nx = static_cast<int>(std::ceil((x1 - x0) / step));
    const int ny = static_cast<int>(std::ceil((y1 - y0) / step));
    const int per_chunk = std::max(1, static_cast<int>(chunk / step));
    const int cx_n = nx / per_chunk + 1, cy_n = ny / per_chunk + 1;
    struct ChunkTex {
      int texture;
      Eigen::Matrix2d A;  // uv = A * xy + off.
      Eigen::Vector2d off;
      float gain;
    };
    std::vector<ChunkTex> chunks(static_cast<size_t>(cx_n) * cy_n);
    for (ChunkTex& c : chunks) {
      c.texture = rng.Int(0, kNumTextures - 1);
      const double phi = rng.Uniform(0, 2 * M_PI);
      c.A << std::cos(phi), -std::sin(phi), std::sin(phi), std::cos(phi);
      c.A *= density_;
      c.off = Eigen::Vector2d(rng.Uniform(0, 1024), rng.Uniform(0, 1024));
      c.gain = static_cast<float>(rng.Uniform(0.85, 1.05));
    }
    auto vertex = [&](int i, int j) {
      const double x = x0 + i * step, y = y0 + j * step;
      return Eigen::Vector3d(x, y, TerrainHeight(x, y));
    };
    for (int i = 0; i < nx; ++i) {
      for (int j = 0; j < ny; ++j) {
        const ChunkTex& c = chunks[static_cast<size_t>(i / per_chunk) * cy_n + j / per_chunk];
        const Eigen::Vector3d p00 = vertex(i, j), p10 = vertex(i + 1, j), p01 = vertex(i, j + 1),
                              p11 = vertex(i + 1, j + 1);
        for (int k = 0; k < 2; ++k) {
          Surface s;
          s.triangle = true;
          s.o_w = k == 0 ? p00 : p11;
          s.a_w = (k == 0 ? p10 : p01) - s.o_w;
          s.b_w = (k == 0 ? p01 : p10) - s.o_w;
          s.texture = c.texture;
          s.uv_o = c.A * s.o_w.head<2>() + c.off;
          s.uv_a = c.A * s.a_w.head<2>();
          s.uv_b = c.A * s.b_w.head<2>();
          s.gain = static_cast<float>(c.gain * Lighting(s.a_w.cross(s.b_w)));
          scene_->surfaces.push_back(s);
        }
        scene_->points_w.push_back(p00);
      }
    }
  }

 private:
  // Diffuse light from a fixed sun plus ambient light; two-sided.
  static double Lighting(const Eigen::Vector3d& normal) {
    const Eigen::Vector3d sun = Eigen::Vector3d(0.4, 0.3, 0.85).normalized();
    return 0.7 + 0.35 * std::abs(normal.normalized().dot(sun));
  }

  Scene* scene_;
  double density_;
  bool flat_light_;
};

// Distance from point q to the footprint rectangle (centre c, yaw, half sizes hl, hd).
double DistanceToFootprint(const Eigen::Vector2d& q, const Eigen::Vector2d& c, double yaw,
                           double hl, double hd) {
  const Eigen::Vector2d d = q - c;
  const double lx = std::abs(d.x() * std::cos(yaw) + d.y() * std::sin(yaw)) - hl;
  const double ly = std::abs(-d.x() * std::sin(yaw) + d.y() * std::cos(yaw)) - hd;
  return Eigen::Vector2d(std::max(lx, 0.0), std::max(ly, 0.0)).norm() +
         std::min(std::max(lx, ly), 0.0);
}

// A box's footprint on the ground: centre, yaw, half length and half depth.
struct Footprint {
  Eigen::Vector2d c;
  double yaw, hl, hd;
};

// Lines both sides of a street (a polyline of path samples) with buildings and crates, starting
// at arc length s0 until s1. Buildings closer than the street half width to any of
// `clearance_samples` are dropped. `placed` (optional): boxes already standing; a new box that
// would overlap one of them is dropped, and the boxes placed are added (a path that drives a
// street twice lines it once).
void LineStreet(SimRng& rng, SceneBuilder& builder, const std::vector<Eigen::Vector2d>& street,
                const std::vector<Eigen::Vector2d>& clearance_samples, double ground_z,
                std::vector<Footprint>* placed = nullptr) {
  std::vector<double> arc(street.size(), 0.0);
  for (size_t i = 1; i < street.size(); ++i)
    arc[i] = arc[i - 1] + (street[i] - street[i - 1]).norm();
  auto at = [&](double s, Eigen::Vector2d* p, Eigen::Vector2d* tangent) {
    const size_t i = std::min<size_t>(
        street.size() - 2, std::upper_bound(arc.begin(), arc.end(), s) - arc.begin() - 1);
    const double a = (s - arc[i]) / std::max(1e-9, arc[i + 1] - arc[i]);
    *p = street[i] + a * (street[i + 1] - street[i]);
    *tangent = (street[i + 1] - street[i]).normalized();
  };
  // Whether a box may stand there; with `placed`, a box that may is recorded as standing.
  auto may_stand = [&](const Eigen::Vector2d& c, double yaw, double hl, double hd, double margin) {
    for (const Eigen::Vector2d& q : clearance_samples) {
      if (DistanceToFootprint(q, c, yaw, hl, hd) < margin) return false;
    }
    if (placed == nullptr) return true;
    // The new box as the disc around its footprint against each standing footprint.
    const double radius = std::hypot(hl, hd);
    for (const Footprint& f : *placed) {
      if (DistanceToFootprint(c, f.c, f.yaw, f.hl, f.hd) < radius) return false;
    }
    placed->push_back({c, yaw, hl, hd});
    return true;
  };
  for (int side : {1, -1}) {
    for (double s = rng.Uniform(0, 4); s < arc.back();) {
      const double length = rng.Uniform(6, 14);
      Eigen::Vector2d p, tangent;
      at(std::min(s + length / 2, arc.back()), &p, &tangent);
      const Eigen::Vector2d normal(-tangent.y(), tangent.x());
      const double depth = rng.Uniform(5, 10), height = rng.Uniform(4, 16);
      const double setback = kStreetHalfWidth + rng.Uniform(0, 1.5);
      const Eigen::Vector2d c = p + side * normal * (setback + depth / 2);
      const double yaw = std::atan2(tangent.y(), tangent.x());
      if (may_stand(c, yaw, length / 2, depth / 2, kStreetHalfWidth - 0.2)) {
        builder.AddBox(rng, c, ground_z, yaw, length, depth, height);
      }
      // Crates on the pavement in front of the buildings.
      if (rng.Uniform() < 0.6) {
        const double size = rng.Uniform(0.4, 1.2);
        const Eigen::Vector2d cc = p + side * normal * rng.Uniform(4.2, 5.5) +
                                   tangent * rng.Uniform(-length / 3, length / 3);
        const double cyaw = yaw + rng.Uniform(-0.4, 0.4);
        if (may_stand(cc, cyaw, size / 2, size / 2, 3.5)) {
          builder.AddBox(rng, cc, ground_z, cyaw, size, size, size * rng.Uniform(0.7, 1.3));
        }
      }
      s += length + rng.Uniform(0.5, 3.0);
    }
  }
}

// Tall buildings on a ring far from the street, so the skyline is textured.
void AddSkyline(SimRng& rng, SceneBuilder& builder, const Eigen::Vector2d& centre, double r0,
                double r1, int count) {
  for (int i = 0; i < count; ++i) {
    const double a = 2 * M_PI * (i + rng.Uniform(0, 0.6)) / count;
    const double r = rng.Uniform(r0, r1);
    const Eigen::Vector2d c = centre + r * Eigen::Vector2d(std::cos(a), std::sin(a));
    builder.AddBox(rng, c, 0.0, a + M_PI / 2 + rng.Uniform(-0.3, 0.3), rng.Uniform(12, 25),
                   rng.Uniform(10, 20), rng.Uniform(15, 40));
  }
}

// Textures are shared between worlds built from the same seed (tests build several sequences
// of one seed): a cache of weak references, so a texture lives as long as a world uses it.
std::shared_ptr<const Texture> CachedTexture(uint64_t seed, TextureStyle style, int side) {
  static std::mutex mutex;
  static std::map<std::tuple<uint64_t, int, int>, std::weak_ptr<const Texture>> cache;
  const auto key = std::make_tuple(seed, static_cast<int>(style), side);
  {
    std::lock_guard<std::mutex> lock(mutex);
    if (auto texture = cache[key].lock()) return texture;
  }
  // Built outside the lock; two threads may both build it, with identical results.
  auto texture = std::make_shared<const Texture>(MakeTextureImage(seed, style, side));
  std::lock_guard<std::mutex> lock(mutex);
  cache[key] = texture;
  return texture;
}

void AddTextures(Scene* scene, uint64_t seed, TextureStyle style, int side) {
  for (int k = 0; k < kNumTextures; ++k) {
    scene->textures.push_back(CachedTexture(MixSeed(seed, 100 + k), style, side));
  }
}

void BuildCity(Scene* scene, uint64_t seed, bool weak, double texel_density_scale,
               double scale = 1.0) {
  SceneBuilder builder(scene, 60.0 * texel_density_scale, weak);
  if (weak) {
    // Overcast: a sky close to the walls' brightness, flat light.
    scene->sky_horizon = 160.f;
    scene->sky_zenith = 150.f;
  }
  SimRng rng(MixSeed(seed, 1));
  std::vector<Eigen::Vector2d> loop;
  for (int i = 0; i <= 2000; ++i) loop.push_back(LoopPoint(2 * M_PI * i / 2000, scale));
  LineStreet(rng, builder, loop, loop, 0.0);
  AddSkyline(rng, builder, Eigen::Vector2d::Zero(), 95 * scale, 140 * scale, 36);
  // The ground is seen close up: a finer texture than the walls.
  SceneBuilder(scene, 80.0 * texel_density_scale, weak)
      .AddGround(-160, 160, -150, 150, 10.0,
                 [&](int ix, int iy) { return SimRng(MixSeed(seed, 2 + ix * 1000 + iy)); });
}

void BuildCorridor(Scene* scene, uint64_t seed, double texel_density_scale) {
  SceneBuilder builder(scene, 60.0 * texel_density_scale);
  // The street the path weaves along (the path itself, sampled; period 50 m).
  const CorridorPath path(1.0);
  std::vector<Eigen::Vector2d> street;
  for (double x = -30; x <= 260; x += 0.5) street.push_back(path.T_w_c(x).translation().head<2>());
  // Segments [x0, x1) each with their own seed; the segment at [140, 185) is the [40, 85)
  // segment moved by +100 m: the same buildings, crates, textures and ground, visited once each.
  struct Segment {
    double x0, x1;
    uint64_t stream;
    double shift;
  };
  const Segment segments[] = {
      {-30, 40, 10, 0}, {40, 85, 11, 0}, {85, 140, 12, 0}, {40, 85, 11, 100}, {185, 260, 14, 0}};
  for (const Segment& seg : segments) {
    Scene part;
    SceneBuilder part_builder(&part, 60.0 * texel_density_scale);
    SimRng rng(MixSeed(seed, seg.stream));
    std::vector<Eigen::Vector2d> sub;
    for (const Eigen::Vector2d& q : street) {
      if (q.x() >= seg.x0 && q.x() <= seg.x1) sub.push_back(q);
    }
    LineStreet(rng, part_builder, sub, street, 0.0);
    // Skyline blocks behind the street fronts.
    for (double x = seg.x0; x < seg.x1; x += rng.Uniform(12, 20)) {
      for (int side : {1, -1}) {
        part_builder.AddBox(rng, {x + 6, side * rng.Uniform(28, 40)}, 0.0, 0.0, rng.Uniform(10, 16),
                            rng.Uniform(8, 14), rng.Uniform(14, 30));
      }
    }
    SceneBuilder(&part, 80.0 * texel_density_scale)
        .AddGround(seg.x0, seg.x1, -60, 60, 5.0, [&](int ix, int iy) {
          return SimRng(MixSeed(seed, seg.stream * 100000 + ix * 1000 + iy));
        });
    const Eigen::Vector3d shift(seg.shift, 0, 0);
    for (Surface s : part.surfaces) {
      s.o_w += shift;
      scene->surfaces.push_back(s);
    }
    for (const Eigen::Vector3d& p : part.points_w) scene->points_w.push_back(p + shift);
  }
}

void BuildTerrain(Scene* scene, uint64_t seed, double texel_density_scale) {
  SceneBuilder builder(scene, 12.0 * texel_density_scale);
  SimRng rng(MixSeed(seed, 20));
  builder.AddTerrain(rng, -360, 360, -300, 300, 8.0, 64.0);
  // A few buildings on the terrain.
  for (int i = 0; i < 40; ++i) {
    const Eigen::Vector2d c(rng.Uniform(-200, 200), rng.Uniform(-120, 120));
    SceneBuilder(scene, 25.0 * texel_density_scale)
        .AddBox(rng, c, TerrainHeight(c.x(), c.y()) - 3.0, rng.Uniform(0, M_PI), rng.Uniform(8, 20),
                rng.Uniform(8, 16), rng.Uniform(6, 18));
  }
  scene->haze_distance = 400.0;
}

// The street world along a recorded path (already placed on the street, RecordedPath): both
// sides of its ground track lined with buildings (a street driven twice is lined once), the
// ground under its bounding box and 60 m around, a skyline ring beyond.
void BuildStreetsAlongPath(Scene* scene, const std::vector<StampedPose>& path, uint64_t seed,
                           double texel_density_scale) {
  // The ground track, a sample every 0.5 m at least (a car standing still adds none).
  std::vector<Eigen::Vector2d> track;
  for (const StampedPose& p : path) {
    const Eigen::Vector2d xy = p.T_w_c.translation().head<2>();
    if (track.empty() || (xy - track.back()).norm() >= 0.5) track.push_back(xy);
  }
  if (track.size() < 2) track.push_back(track.back() + Eigen::Vector2d(0.5, 0.0));
  Eigen::Vector2d lo = track[0], hi = track[0];
  for (const Eigen::Vector2d& q : track) {
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  SceneBuilder builder(scene, 60.0 * texel_density_scale);
  SimRng rng(MixSeed(seed, 30));
  std::vector<Footprint> placed;
  LineStreet(rng, builder, track, track, 0.0, &placed);
  const Eigen::Vector2d centre = (lo + hi) / 2;
  const double r0 = (hi - lo).norm() / 2 + 60.0;
  AddSkyline(rng, builder, centre, r0, r0 + 50.0,
             std::max(36, static_cast<int>(2 * M_PI * r0 / 40.0)));
  SceneBuilder(scene, 80.0 * texel_density_scale)
      .AddGround(lo.x() - 60, hi.x() + 60, lo.y() - 60, hi.y() + 60, 10.0, [&](int ix, int iy) {
        return SimRng(MixSeed(seed, 1000000 + static_cast<uint64_t>(ix + 100000),
                              static_cast<uint64_t>(iy + 100000)));
      });
}

}  // namespace

World BuildWorldAlongPath(const std::vector<StampedPose>& placed_path, uint64_t seed,
                          int texture_size, double texel_density_scale) {
  World world;
  BuildStreetsAlongPath(&world.scene, placed_path, seed, texel_density_scale);
  world.path = std::make_unique<RecordedPath>(placed_path);
  AddTextures(&world.scene, seed, TextureStyle::kRich, texture_size);
  return world;
}

const std::vector<PresetInfo>& Presets() {
  static const std::vector<PresetInfo> presets = {
      {"rover_loop",
       "ground rover, one loop (~250 m, 2.5 m/s) of a street circuit between buildings", 100.0},
      {"flight", "6-DoF blimp-like figure eight 30-40 m over textured terrain, looking down",
       120.0},
      {"rotation", "pure rotation in place (a full turn) in the middle of a street", 20.0},
      {"fast",
       "the rover loop at ~6 m/s with jerky heading, pitch, roll, height and sideways motion",
       40.0},
      {"low_texture", "the rover loop in a city of weak, sparse texture", 100.0},
      {"small_loop",
       "the rover loop's street circuit at half size (~125 m, 2.5 m/s) in its own city: a "
       "short closed loop for loop-closure tests",
       50.0},
      {"false_loop",
       "straight 200 m street whose stretches at x=40-85 m and x=140-185 m look identical "
       "(not a loop)",
       100.0},
  };
  return presets;
}

const PresetInfo* FindPreset(const std::string& name) {
  for (const PresetInfo& p : Presets()) {
    if (p.name == name) return &p;
  }
  return nullptr;
}

World BuildWorld(const std::string& preset, uint64_t seed, int texture_size,
                 double texel_density_scale) {
  const PresetInfo* info = FindPreset(preset);
  CHECK(info != nullptr) << "unknown synthetic preset '" << preset << "'";
  World world;
  TextureStyle style = TextureStyle::kRich;
  if (preset == "rover_loop" || preset == "rotation" || preset == "low_texture") {
    BuildCity(&world.scene, seed, preset == "low_texture", texel_density_scale);
    if (preset == "rotation") {
      world.path = std::make_unique<RotationPath>(info->duration_s);
    } else {
      world.path = std::make_unique<LoopPath>(info->duration_s, false);
    }
    if (preset == "low_texture") style = TextureStyle::kWeak;
  } else if (preset == "fast") {
    BuildCity(&world.scene, seed, false, texel_density_scale);
    world.path = std::make_unique<LoopPath>(info->duration_s, true);
  } else if (preset == "small_loop") {
    BuildCity(&world.scene, seed, false, texel_density_scale, kSmallLoopScale);
    world.path = std::make_unique<LoopPath>(info->duration_s, false, kSmallLoopScale);
  } else if (preset == "flight") {
    BuildTerrain(&world.scene, seed, texel_density_scale);
    world.path = std::make_unique<FlightPath>(info->duration_s);
  } else if (preset == "false_loop") {
    BuildCorridor(&world.scene, seed, texel_density_scale);
    world.path = std::make_unique<CorridorPath>(2.0);
  }
  AddTextures(&world.scene, seed, style, texture_size);
  return world;
}

}  // namespace dala::sim
