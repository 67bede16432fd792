#pragma once
// Reading an input file (issue 44): scene TOML, OBJ, MTL and kernel files all come through here, so
// each is opened only if it is a regular file, and read up to a size bound. A FIFO named as an
// input would block the read forever, /dev/zero or a huge sparse file would be read without end
// (and end in "out of host memory", the wrong advice), a directory reads as nothing: each is
// refused with one line naming the path instead.
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>

namespace raysort {

// What an input file is, for messages ("scene file", "OBJ file", "MTL file", "kernel file",
// "encoder file"), and the most bytes it may have.
struct InputKind {
  std::string_view what;       // "OBJ file"
  std::string_view fix;        // what to do instead: "give the path of the .obj file"
  std::uint64_t max_bytes;
};

// Bounds. Real inputs are far below them (scenes/*.toml ≤ 4 KB, the largest real OBJ 12 MB, MTL
// files ≤ 4 KB, cl/ files ≤ 24 KB); each leaves room for hand-made larger ones, and keeps a
// corrupt or hostile file from taking the host's memory before any other check runs.
// OBJ: 4 GiB of text is ~60 M triangles, past what the scene loader's 512 B/triangle estimate lets
// most hosts hold anyway.
inline constexpr InputKind kSceneFile{"scene file", "give the path of a .toml scene file", std::uint64_t(16) << 20};
inline constexpr InputKind kObjFile{"OBJ file", "give the path of the .obj file", std::uint64_t(4) << 30};
inline constexpr InputKind kMtlFile{"MTL file", "give the path of the .mtl file, or remove the mtllib line", std::uint64_t(64) << 20};
inline constexpr InputKind kKernelFile{"kernel file", "point --kernels at the repository's cl/ folder", std::uint64_t(16) << 20};
// Scene files of other formats (scene/mesh_formats.h): a PLY or a glTF binary holds ~50 B per
// triangle, so the OBJ bound; a pbrt-v4 file (and each file it includes) likewise.
inline constexpr InputKind kPlyFile{"PLY file", "give the path of the .ply file", std::uint64_t(4) << 30};
inline constexpr InputKind kGltfFile{"glTF file", "give the path of the .gltf or .glb file", std::uint64_t(4) << 30};
inline constexpr InputKind kGltfBuffer{"glTF buffer", "give the .bin file the glTF names, beside it", std::uint64_t(4) << 30};
inline constexpr InputKind kPbrtFile{"pbrt-v4 file", "give the path of the .pbrt file", std::uint64_t(4) << 30};
// An encoder from a file (--encoders file:PATH): one OpenCL C function, a few KB; the kernel files' bound.
inline constexpr InputKind kEncoderFile{"encoder file",
                                        "give the path of an OpenCL C file that defines rs_file_code (docs/encoders.md, "
                                        "\"An encoder from a file\")",
                                        std::uint64_t(16) << 20};

// Reads `path` whole. Throws Error naming the kind and the path when it does not exist, cannot be
// opened, is not a regular file (a directory, FIFO, device or socket), or is (or grows) larger than
// kind.max_bytes. `inspect`, when given, sees each chunk as it is read (at most 64 KiB), before the
// next is read, so a content check can refuse a file early (an overlong OBJ line after 1 MiB,
// however large the file).
std::string read_input_file(const std::string& path, const InputKind& kind,
                            const std::function<void(const char*, std::size_t)>& inspect = {});

// The checks of read_input_file without reading (stat): throws the same Error for a path that
// cannot be read as this kind of input. For commands that refuse a reference before any work.
void check_input_file(const std::string& path, const InputKind& kind);

}  // namespace raysort
