#!/usr/bin/env python3
"""Regenerates the hostile inputs in tests/bad/ and the samples in tests/good/.

The files are committed; this script only documents how the binary ones were
made. Run from anywhere: python3 tests/bad/generate.py
Every file in tests/bad/ has a row in tests/bad/EXPECTED.txt (kept by hand).
"""
import os
import random
import struct

BAD = os.path.dirname(os.path.abspath(__file__))
GOOD = os.path.join(os.path.dirname(BAD), 'good')

# The points every file in tests/good/ holds, in this order. All are exact
# in binary32, so float PLY files carry them unchanged.
POINTS = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (1, 1, 0),
          (0, 0, 1), (1, 0, 1), (0, 1, 1), (1, 1, 1),
          (0.5, 0.25, 0.75), (0.25, -0.125, 1.5)]


def put(directory, name, data):
    if isinstance(data, str):
        data = data.encode('latin-1')
    with open(os.path.join(directory, name), 'wb') as f:
        f.write(data)


def ply_header(fmt, elements):
    """elements: [(name, count, [property lines])]"""
    h = 'ply\nformat %s 1.0\ncomment made by tests/bad/generate.py\n' % fmt
    for name, count, props in elements:
        h += 'element %s %d\n' % (name, count)
        for p in props:
            h += 'property %s\n' % p
    return (h + 'end_header\n').encode('ascii')


def bad():
    put(BAD, 'empty.xyz', '')
    put(BAD, 'comments_only.xyz', '# nothing but comments\n\n   # and blanks\n')
    put(BAD, 'two_numbers.xyz', '0 0 0\n1 0 0\n0 1\n0 0 1\n')
    put(BAD, 'four_numbers.xyz', '0 0 0\n1 0 0 7\n0 1 0\n0 0 1\n')
    put(BAD, 'letters.xyz', '0 0 0\n1.0abc 0 0\n0 1 0\n0 0 1\n')
    put(BAD, 'nan.xyz', '0 0 0\n1 NaN 0\n0 1 0\n0 0 1\n')
    put(BAD, 'inf.xyz', '0 0 0\n1 0 0\n0 1 -Infinity\n0 0 1\n')
    put(BAD, 'overflow.xyz', '0 0 0\n1e999 0 0\n0 1 0\n0 0 1\n')
    put(BAD, 'underflow.xyz', '0 0 0\n1 1e-400 0\n0 1 0\n0 0 1\n')
    put(BAD, 'subnormal.xyz', '0 0 0\n1 0 0\n0 1 0\n0 0 4.9e-324\n')
    put(BAD, 'hexfloat.xyz', '0 0 0\n0x1p3 0 0\n0 1 0\n0 0 1\n')
    put(BAD, 'stray_comma.xyz', '0,0,0\n1,,0,0\n0,1,0\n0,0,1\n')
    put(BAD, 'quote_open.csv', '0,0,0\n1,0,0\n"0,1,0\n0,0,1\n')
    put(BAD, 'quote_text.csv', '0,0,0\n1,0,0\n"0"1,1,0\n0,0,1\n')
    put(BAD, 'nul_byte.xyz', '0 0 0\n1 0 0\n0 1\x000\n0 0 1\n')
    put(BAD, 'crlf_four.txt', '0 0 0\r\n1 0 0\r\n0 1 0 1\r\n0 0 1\r\n')
    rnd = random.Random(20240601)
    put(BAD, 'random_bytes.xyz', bytes(rnd.randrange(256) for _ in range(300)))
    put(BAD, 'unknown_ext.las', '0,0,0\n1,0,0\n0,1,0\n0,0,1\n')

    node = ['%d %s\n' % (i, ' '.join(repr(float(v)) for v in p))
            for i, p in enumerate(POINTS[:4])]
    put(BAD, 'node_count_high.node', '5 3 0 0\n' + ''.join(node))
    put(BAD, 'node_count_low.node', '3 3 0 0\n' + ''.join(node))
    put(BAD, 'node_dim2.node', '4 2 0 0\n0 0 0\n1 1 0\n2 0 1\n3 1 1\n')
    put(BAD, 'node_index_gap.node',
        '# TetGen node file\n4 3 0 0\n0 0 0 0\n1 1 0 0\n3 0 1 0\n4 0 0 1\n')
    put(BAD, 'node_first_index.node', '4 3 0 0\n2 0 0 0\n3 1 0 0\n4 0 1 0\n5 0 0 1\n')
    put(BAD, 'node_huge_count.node', '4000000000 3 0 0\n' + ''.join(node))
    put(BAD, 'node_count_overflow.node',
        '99999999999999999999999 3 0 0\n' + ''.join(node))
    put(BAD, 'node_fields.node',
        '4 3 1 1\n0 0 0 0 0.5 1\n1 1 0 0 0.5\n2 0 1 0 0.5 1\n3 0 0 1 0.5 0\n')
    put(BAD, 'node_letters.node', '4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 one 0\n3 0 0 1\n')

    put(BAD, 'ply_not_ply.ply', 'PLY\nformat ascii 1.0\nelement vertex 0\nend_header\n')
    put(BAD, 'ply_random.ply', bytes(rnd.randrange(256) for _ in range(300)))
    put(BAD, 'ply_no_end_header.ply',
        'ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n'
        'property float y\nproperty float z\n0 0 0\n')
    put(BAD, 'ply_bad_format.ply',
        'ply\nformat binary_middle_endian 1.0\nelement vertex 1\n'
        'property float x\nproperty float y\nproperty float z\nend_header\n')
    put(BAD, 'ply_unknown_type.ply',
        'ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n'
        'property float128 y\nproperty float z\nend_header\n0 0 0\n')
    put(BAD, 'ply_no_z.ply',
        'ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n'
        'property float y\nproperty float w\nend_header\n0 0 0\n')
    put(BAD, 'ply_list_x.ply',
        'ply\nformat ascii 1.0\nelement vertex 1\nproperty list uchar float x\n'
        'property float y\nproperty float z\nend_header\n1 0 0 0\n')
    put(BAD, 'ply_count_negative.ply',
        'ply\nformat ascii 1.0\nelement vertex -3\nproperty float x\n'
        'property float y\nproperty float z\nend_header\n0 0 0\n')
    put(BAD, 'ply_count_overflow.ply',
        'ply\nformat ascii 1.0\nelement vertex 99999999999999999999999\n'
        'property float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n')

    xyzf = ['float x', 'float y', 'float z']
    xyzd = ['double x', 'double y', 'double z']
    # 10 vertices of 12 bytes, cut in the middle of vertex 7
    hdr = ply_header('binary_little_endian', [('vertex', 10, xyzf)])
    body = b''.join(struct.pack('<3f', *p) for p in POINTS)
    put(BAD, 'ply_truncated_le.ply', hdr + body[:6 * 12 + 5])
    # faces after the vertices, cut inside face 2
    hdr = ply_header('binary_big_endian',
                     [('vertex', 4, xyzd), ('face', 3, ['list uchar int vertex_indices'])])
    body = b''.join(struct.pack('>3d', *p) for p in POINTS[:4])
    faces = b''.join(struct.pack('>B3i', 3, 0, 1, 2) for _ in range(3))
    put(BAD, 'ply_truncated_face.ply', hdr + body + faces[:13 + 6])
    hdr = ply_header('binary_little_endian', [('vertex', 4000000000, xyzf)])
    put(BAD, 'ply_huge_count.ply',
        hdr + b''.join(struct.pack('<3f', *p) for p in POINTS[:4]))
    hdr = ply_header('ascii', [('vertex', 4000000000, xyzf)])
    put(BAD, 'ply_ascii_huge_count.ply', hdr + b'0 0 0\n1 0 0\n0 1 0\n0 0 1\n')
    four = b'0.0 0.0 0.0\n1.0 0.0 0.0\n0.0 1.0 0.0\n0.0 0.0 1.0\n'
    hdr = ply_header('ascii', [('vertex', 5, xyzf)])
    put(BAD, 'ply_count_high_ascii.ply', hdr + four)
    hdr = ply_header('ascii', [('vertex', 3, xyzf)])
    put(BAD, 'ply_count_low_ascii.ply', hdr + four)
    hdr = ply_header('binary_little_endian', [('vertex', 3, xyzf)])
    put(BAD, 'ply_count_low_bin.ply',
        hdr + b''.join(struct.pack('<3f', *p) for p in POINTS[:4]))
    hdr = ply_header('binary_little_endian', [('vertex', 3, xyzf)])
    put(BAD, 'ply_nan_le.ply',
        hdr + struct.pack('<3f', 0, 0, 0) + struct.pack('<3f', 1, float('nan'), 0)
        + struct.pack('<3f', 0, 1, 0))
    hdr = ply_header('binary_big_endian', [('vertex', 3, xyzd)])
    put(BAD, 'ply_inf_be.ply',
        hdr + struct.pack('>3d', 0, 0, 0) + struct.pack('>3d', 1, 0, 0)
        + struct.pack('>3d', 0, 1, float('-inf')))
    hdr = ply_header('ascii', [('vertex', 3, xyzf)])
    put(BAD, 'ply_ascii_nan.ply', hdr + b'0.0 0.0 0.0\n1.0 nan 0.0\n0.0 1.0 0.0\n')
    put(BAD, 'ply_ascii_fields.ply', hdr + b'0.0 0.0 0.0\n1.0 0.0\n0.0 1.0 0.0\n')
    put(BAD, 'ply_ascii_overflow.ply', hdr + b'0.0 0.0 0.0\n1.0 0.0 0.0\n0.0 1e999 0.0\n')
    hdr = ply_header('binary_little_endian',
                     [('face', 2, ['list char int vertex_indices']), ('vertex', 4, xyzf)])
    put(BAD, 'ply_negative_list.ply',
        hdr + struct.pack('<b3i', 3, 0, 1, 2) + struct.pack('<b', -2)
        + b''.join(struct.pack('<3f', *p) for p in POINTS[:4]))


def degenerate():
    """Files every reader accepts and the library refuses (exit 2 from the
    CLI): their EXPECTED.txt messages come from src/front/seed.c and name
    'distinct point'."""
    put(BAD, 'three_points.xyz', '0 0 0\n1 0 0\n0 1 0\n')
    put(BAD, 'repeated_point.xyz', '1.5 -2 3\n' * 4000)
    put(BAD, 'repeated_three.ply',
        ply_header('binary_little_endian',
                   [('vertex', 3000, ['float x', 'float y', 'float z'])])
        + b''.join(struct.pack('<3f', *POINTS[i % 3]) for i in range(3000)))
    put(BAD, 'collinear.xyz',
        ''.join('%d %d %d\n' % (i, 2 * i, 3 * i) for i in (3, 0, 5, 1, 4, 2, 1)))
    put(BAD, 'coplanar.node',
        '9 3 0 0\n' + ''.join('%d %d %d %d\n' % (k, i, j, 1 - i - j)
                             for k, (i, j) in enumerate(
                                 (a, b) for a in range(3) for b in range(3))))


def more_bad():
    """Hostile inputs added after the first corpus (kept apart so the
    random bytes drawn above stay the same)."""
    rnd = random.Random(20240602)
    put(BAD, 'random_bytes.node', bytes(rnd.randrange(256) for _ in range(300)))
    put(BAD, 'node_overflow.node', '4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 -1e400 0\n3 0 0 1\n')
    put(BAD, 'node_inf.node', '4 3\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 inf\n')
    put(BAD, 'ply_header_garbage.ply',
        b'ply\nformat binary_little_endian 1.0\nelement vertex 1\n'
        b'property float x\n\x00\x13\xfe\xffgarbage\nproperty float y\n'
        b'property float z\nend_header\n' + struct.pack('<3f', 0, 0, 0))
    put(BAD, 'ply_header_cut.ply',
        'ply\nformat binary_big_endian 1.0\nelement vertex 4\nproperty float x\n'
        'property float y\n')
    # a bit flipped in the exponent of vertex 2's y: 1.0f becomes Inf
    hdr = ply_header('binary_little_endian', [('vertex', 4, ['float x', 'float y', 'float z'])])
    body = bytearray(b''.join(struct.pack('<3f', *p) for p in POINTS[:4]))
    body[2 * 12 + 4 + 3] |= 0x40
    put(BAD, 'ply_bitflip_le.ply', hdr + bytes(body))
    # counts a point index can hold (below 2^31) that the bytes cannot:
    # refused before allocating (tests/test_faults.c checks no allocation
    # grows with the count)
    node = ['%d %s\n' % (i, ' '.join(repr(float(v)) for v in p))
            for i, p in enumerate(POINTS[:4])]
    put(BAD, 'node_big_count.node', '2000000000 3 0 0\n' + ''.join(node))
    hdr = ply_header('binary_little_endian', [('vertex', 2000000000, ['float x', 'float y', 'float z'])])
    put(BAD, 'ply_big_count.ply', hdr + b''.join(struct.pack('<3f', *p) for p in POINTS[:4]))
    hdr = ply_header('ascii', [('vertex', 2000000000, ['float x', 'float y', 'float z']),
                               ('face', 1, ['list uchar int vertex_indices'])])
    put(BAD, 'ply_ascii_big_count.ply', hdr + b'0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n')


def good():
    # plain text, with everything the format allows
    lines = ['# ten points: the unit cube and two more', '']
    for i, p in enumerate(POINTS):
        s = ' '.join(repr(float(v)) for v in p)
        if i == 3:
            s = '  %s\t# trailing comment' % s.replace(' ', '\t')
        if i == 5:
            s = '1E+0 0e0 +1.0e-0'
        lines.append(s)
    put(GOOD, 'cube10.xyz', '\n'.join(lines) + '\n')
    put(GOOD, 'cube10_crlf_commas.TXT',
        '\xef\xbb\xbf' + ''.join('%r, %r,%r\r\n' % tuple(float(v) for v in p)
                                 for p in POINTS))
    # CSV as spreadsheets and PDAL write it: a quoted header, quoted
    # numbers, a quoted text column with a comma and doubled quotes, one
    # line unquoted and one with blanks around its quotes
    words = ['ground, bare', '2', '2', 'a ""quoted"" word', '', '2', '2', '2', '2', '2']
    rows = ['"%r","%r","%r","%s"' % (tuple(float(v) for v in p) + (w,))
            for p, w in zip(POINTS, words)]
    rows[6] = '%r,%r,%r,2' % tuple(float(v) for v in POINTS[6])
    rows[7] = '"%r", "%r" ,"%r",2' % tuple(float(v) for v in POINTS[7])
    put(GOOD, 'cube10_quoted.csv', '"X","Y","Z","Classification"\n' + '\n'.join(rows) + '\n')
    put(GOOD, 'cube10.node',
        '# TetGen: 1-based, one attribute, markers\n%d 3 1 1\n' % len(POINTS)
        + ''.join('%d  %r %r %r  %g %d\n' % ((i + 1,) + p + (0.5 * i, i % 2))
                  for i, p in enumerate(POINTS)))
    xyz_ascii = [('vertex', len(POINTS),
                  ['float x', 'uchar red', 'double y', 'float z', 'list uchar int idx'])]
    body = ''.join('%r %d %r %r 2 %d %d\n' % (p[0], i, p[1], p[2], i, i + 1)
                   for i, p in enumerate(POINTS))
    put(GOOD, 'cube10_ascii.ply',
        ply_header('ascii', [('material', 2, ['list uchar float rgb', 'int id'])]
                   + xyz_ascii + [('face', 1, ['list uchar int vertex_indices'])])
        + b'3 0.5 0.5 0.5 1\n0 2\n' + body.encode() + b'3 0 1 2\n')
    for fmt, e in (('binary_little_endian', '<'), ('binary_big_endian', '>')):
        hdr = ply_header(fmt, [('camera', 1, ['float fx', 'list ushort short k']),
                               ('vertex', len(POINTS),
                                ['short id', 'float x', 'float y', 'float z',
                                 'uint8 alpha', 'float64 confidence']),
                               ('face', 2, ['list uchar int vertex_indices'])])
        cam = struct.pack(e + 'fH3h', 500.0, 3, -1, 0, 1)
        verts = b''.join(struct.pack(e + 'h3fBd', i, *p, 255, 0.5)
                         for i, p in enumerate(POINTS))
        faces = struct.pack(e + 'B3i', 3, 0, 1, 2) + struct.pack(e + 'B4i', 4, 4, 5, 6, 7)
        name = 'cube10_le.ply' if e == '<' else 'cube10_be.ply'
        put(GOOD, name, hdr + cum(cam, verts, faces))
    hdr = ply_header('binary_big_endian', [('vertex', len(POINTS), [
        'double z', 'double y', 'double x'])])
    put(GOOD, 'cube10_be_double_zyx.ply',
        hdr + b''.join(struct.pack('>3d', p[2], p[1], p[0]) for p in POINTS))


def cum(*parts):
    return b''.join(parts)


if __name__ == '__main__':
    os.makedirs(GOOD, exist_ok=True)
    bad()
    degenerate()
    more_bad()
    good()
