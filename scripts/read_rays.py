#!/usr/bin/env python3
"""Reads a raysort ray batch file (docs/rays-format.md). python3 scripts/read_rays.py FILE"""
import struct
import sys


def read_rays(path):
    data = open(path, "rb").read()
    if data[:8] != b"RSRAYS\r\n":
        sys.exit(f"{path}: not a raysort ray batch (bad magic)")
    version, flags, n = struct.unpack_from("<IIQ", data, 8)
    if version != 1:
        sys.exit(f"{path}: format version {version}; this reader reads version 1")
    name_len, command_len = struct.unpack_from("<II", data, 56)
    rays_at = 64 + name_len + command_len
    has_hits = bool(flags & 1)
    if len(data) != rays_at + n * (32 + 8 * has_hits):
        sys.exit(f"{path}: {len(data)} bytes do not hold the {n} rays its header counts")
    hits_at = rays_at + 32 * n
    return {"batch": data[64:64 + name_len].decode(), "any_hit": bool(flags & 2),
            "scene_sha256": data[24:56].hex(), "command": data[64 + name_len:rays_at].decode(),
            # per ray: origin x y z, direction x y z, tmin, tmax; per hit: t, triangle id (0xFFFFFFFF: miss)
            "rays": [struct.unpack_from("<8f", data, rays_at + 32 * i) for i in range(n)],
            "hits": [struct.unpack_from("<fI", data, hits_at + 8 * i) for i in range(n)] if has_hits else None}


if __name__ == "__main__":
    b = read_rays(sys.argv[1])
    print(f"batch {b['batch']}: {len(b['rays'])} rays, any hit {b['any_hit']}, hits {b['hits'] is not None}, "
          f"scene sha256 {b['scene_sha256']}, made by: {b['command']}")
