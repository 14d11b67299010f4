#!/usr/bin/env python3
"""Writes the hand-made seeds of the fuzz_mesh corpus (tests/fuzz/corpus/mesh).

Encoding (tests/fuzz/fuzz_mesh.c): byte 0 holds flags (bits 0-1 scale:
1, 2^-498, 2^498, mixed; bit 2 offset 2^30 with extent 2^-20; bit 3
neighbours), then 3 signed bytes a point, 4 in mixed mode (the 4th picks the
point's power of two). The rest of the corpus is what libFuzzer kept.
Run from anywhere: python3 tests/fuzz/mesh_seeds.py
"""
import os
import struct

OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), 'corpus', 'mesh')


def pts(points, flags, mixed_exp=None):
    b = bytes([flags])
    for i, p in enumerate(points):
        b += struct.pack('3b', *p)
        if flags & 3 == 3:
            b += bytes([mixed_exp[i % len(mixed_exp)]])
    return b


def main():
    os.makedirs(OUT, exist_ok=True)
    lattice = [(a, b, c) for a in range(3) for b in range(3) for c in range(3)]
    cube_oct = [(x, y, z) for x in (-2, 2) for y in (-2, 2) for z in (-2, 2)] + \
        [(3, 0, 0), (-3, 0, 0), (0, 3, 0), (0, -3, 0), (0, 0, 3), (0, 0, -3), (0, 0, 0)]
    plane = [(a, b, 0) for a in range(4) for b in range(3)]
    line = [(i, 2 * i, 3 * i) for i in range(6)]
    seeds = {
        'lattice': pts(lattice, 0x08),
        'lattice_tiny': pts(lattice, 0x01),
        'lattice_huge': pts(lattice, 0x0a),
        'lattice_mixed': pts(lattice, 0x0b, [0, 6, 3, 1, 5]),
        'lattice_offset': pts(lattice, 0x0c),
        'cube_octahedron': pts(cube_oct, 0x08),
        'dups': pts(lattice[:6] * 5, 0x08),
        'plane': pts(plane, 0x00),
        'line': pts(line, 0x00),
        'two': pts(lattice[:2], 0x08),
    }
    for name, data in seeds.items():
        with open(os.path.join(OUT, 'seed_' + name), 'wb') as f:
            f.write(data)


if __name__ == '__main__':
    main()
