#pragma once
// FNV-1a 64 (Fowler–Noll–Vo), the suite's one non-cryptographic hash: fingerprints of keys, orders,
// shard plans and kernel sources, short names for long cell ids, and seeds drawn from names. Its
// values are in committed result sets and seed the shuffled baseline and the rounds' arm orders,
// so it is written once, here.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace raysort {

inline constexpr std::uint64_t kFnv1aOffsetBasis = 0xcbf29ce484222325ull;
inline constexpr std::uint64_t kFnv1aPrime = 0x100000001b3ull;

// The hash of `bytes` raw bytes, continuing from h (a hash of what came before; the offset basis
// to start), so that several pieces hash as their concatenation. (Named apart from the text
// overload: fnv1a("x", h) would otherwise pick this one and read h bytes.)
inline std::uint64_t fnv1a_bytes(const void* data, std::size_t bytes, std::uint64_t h = kFnv1aOffsetBasis) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < bytes; ++i) h = (h ^ p[i]) * kFnv1aPrime;
  return h;
}
inline std::uint64_t fnv1a(std::string_view text, std::uint64_t h = kFnv1aOffsetBasis) {
  return fnv1a_bytes(text.data(), text.size(), h);
}

// The hash of raw bytes as 16 hex digits (keys_hash, order_hash, plan_hash).
std::string fnv1a_hex(const void* data, std::size_t bytes);

}  // namespace raysort
