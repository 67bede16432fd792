#pragma once
// Procedural mesh generators: deterministic functions of their parameters and seed, so the
// embedded scenes (docs/design.md, "Scenes") need no files and are identical on every machine.
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "scene/scene.h"

namespace raysort {

// Parameters of a generator as read from a scene file: numbers and 3-vectors by name.
struct GeneratorParams {
  std::map<std::string, double> numbers;
  std::map<std::string, Vec3> vectors;
  double number(const std::string& key, double fallback) const {
    auto it = numbers.find(key);
    return it == numbers.end() ? fallback : it->second;
  }
  Vec3 vector(const std::string& key, Vec3 fallback) const {
    auto it = vectors.find(key);
    return it == vectors.end() ? fallback : it->second;
  }
};

// Names of all generators, for error messages and docs.
std::vector<std::string> generator_names();

// Builds the mesh of generator `name` (one of generator_names()); throws Error naming the valid
// generators or the offending parameter.
Mesh generate_mesh(const std::string& name, const GeneratorParams& params, std::uint64_t seed);

// How many triangles generate_mesh would make (at most), without making them; throws the same
// Error for an unknown generator or a bad parameter.
std::uint64_t generated_triangle_count(const std::string& name, const GeneratorParams& params);

}  // namespace raysort
