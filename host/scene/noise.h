#pragma once
// Deterministic randomness for scene generation: a splitmix64 stream and hashed value noise.
// Only integer arithmetic and + − × on doubles, so every standard library and machine gives
// the same scenes (std::uniform_*_distribution differ between libstdc++, libc++ and MSVC).
#include <cmath>
#include <cstdint>

namespace raysort {

// splitmix64 (Steele, Lea, Flood 2014): a 64-bit counter through a bijective mixer.
class SceneRng {
 public:
  explicit SceneRng(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next_u64() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  // Uniform in [0, 1): the top 53 bits.
  double uniform() { return static_cast<double>(next_u64() >> 11) * (1.0 / 9007199254740992.0); }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }

 private:
  std::uint64_t state_;
};

// Hash of an integer lattice point and a seed to [0, 1).
inline double lattice_hash(std::int64_t x, std::int64_t y, std::int64_t z, std::uint64_t seed) {
  std::uint64_t h = seed * 0x9E3779B97F4A7C15ull;
  h ^= static_cast<std::uint64_t>(x) * 0xC2B2AE3D27D4EB4Full;
  h = (h ^ (h >> 31)) * 0xBF58476D1CE4E5B9ull;
  h ^= static_cast<std::uint64_t>(y) * 0x165667B19E3779F9ull;
  h = (h ^ (h >> 29)) * 0x94D049BB133111EBull;
  h ^= static_cast<std::uint64_t>(z) * 0x27D4EB2F165667C5ull;
  h = (h ^ (h >> 32)) * 0xD6E8FEB86659FD93ull;
  h ^= h >> 32;
  return static_cast<double>(h >> 11) * (1.0 / 9007199254740992.0);
}

// Trilinear value noise with a smoothstep fade, in [0, 1).
inline double value_noise(double x, double y, double z, std::uint64_t seed) {
  double fx = std::floor(x), fy = std::floor(y), fz = std::floor(z);
  auto ix = static_cast<std::int64_t>(fx), iy = static_cast<std::int64_t>(fy), iz = static_cast<std::int64_t>(fz);
  double tx = x - fx, ty = y - fy, tz = z - fz;
  tx = tx * tx * (3.0 - 2.0 * tx);
  ty = ty * ty * (3.0 - 2.0 * ty);
  tz = tz * tz * (3.0 - 2.0 * tz);
  auto lerp = [](double a, double b, double t) { return a + (b - a) * t; };
  double c[2][2];
  for (int dz = 0; dz < 2; ++dz)
    for (int dy = 0; dy < 2; ++dy)
      c[dz][dy] = lerp(lattice_hash(ix, iy + dy, iz + dz, seed), lattice_hash(ix + 1, iy + dy, iz + dz, seed), tx);
  return lerp(lerp(c[0][0], c[0][1], ty), lerp(c[1][0], c[1][1], ty), tz);
}

// Fractional Brownian motion: `octaves` of value noise, lacunarity 2, gain 0.5, in about [-1, 1].
inline double fbm(double x, double y, double z, int octaves, std::uint64_t seed) {
  double sum = 0.0, amp = 1.0, norm = 0.0;
  for (int o = 0; o < octaves; ++o) {
    sum += amp * (2.0 * value_noise(x, y, z, seed + static_cast<std::uint64_t>(o) * 7919u) - 1.0);
    norm += amp;
    amp *= 0.5;
    x *= 2.0;
    y *= 2.0;
    z *= 2.0;
  }
  return norm > 0.0 ? sum / norm : 0.0;
}

}  // namespace raysort
