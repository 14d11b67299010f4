#!/usr/bin/env python3
"""Tests of the benchmark harness itself (bench/run), on 2,000 points.

  selftest.py RUN FRONTDT GEN_POINTS MEASURE CMP_CGAL|none [TETSHASH]

1. A real run (frontdt serial and shared at 1 and 2 threads, CGAL when
   built): every row ok, every frontdt row checked against the reference,
   peak RSS below the runner's own (bench/measure does its job), summary
   and CSV written.
2. A frontdt that prints a wrong hash in message mode: those rows are
   'wrong', kept out of the summary's medians, and the runner exits 3.
3. A frontdt that refuses the parallel modes the way an engine without
   them does ("not available"): rows 'unavailable', exit 0.
With TETSHASH (bench/tetshash), the HXT and Geogram columns, played by
stand-ins that run frontdt (building the real drivers takes a minute):
4. On uniform points the stand-in HXT's tets (written by the untimed check
   run) match the reference, the stand-in Geogram drops a tet and is
   'differs (unique mesh)' without failing the run; the four-code table,
   CPU times and frontdt's per-face figures are there.
5. On the lattice (ties broken freely) only the counts are compared.
6. A peer build (--peers-src's build.sh) that makes hxt_dt and then fails:
   HXT runs, Geogram's rows are 'unavailable' and say why; a second run
   that asks for HXT alone reuses it without building.
Exit 0 when all hold, 1 otherwise (the failing check is printed).
"""

import csv
import os
import subprocess
import sys
import tempfile

FAILS = []


def check(cond, what):
    if not cond:
        FAILS.append(what)
        print('FAIL:', what, flush=True)


def wrapper(folder, name, frontdt, body):
    """A stand-in for frontdt: a Python script that runs the real one and
    then does body (which sees argv, the result r and the real path)."""
    path = os.path.join(folder, name)
    with open(path, 'w') as f:
        f.write('#!%s\nimport subprocess, sys\nargv = sys.argv[1:]\n'
                'real = %r\n%s\n' % (sys.executable, frontdt, body))
    os.chmod(path, 0o755)
    return path


def stand_in_peer(folder, name, code, frontdt, drop):
    """A stand-in for ../shared/peers' hxt_dt or geogram_dt: the same
    command line and SUMMARY line, its tets computed by frontdt; with drop
    it loses one tet, in its file and its count."""
    path = os.path.join(folder, name)
    with open(path, 'w') as f:
        f.write('#!%s\n' % sys.executable + (
            'import os, subprocess, sys, tempfile\n'
            'args, t = sys.argv[1:], 1\n'
            'if args[:1] == ["--threads"]:\n'
            '    t, args = int(args[1]), args[2:]\n'
            'fd, tmp = tempfile.mkstemp(suffix=".tets")\n'
            'os.close(fd)\n'
            'r = subprocess.run([%r, args[0], "-o", tmp, "--quiet"])\n'
            'if r.returncode:\n'
            '    sys.exit(r.returncode)\n'
            'lines = open(tmp).readlines()\n'
            'os.unlink(tmp)\n'
            'if %r:\n'
            '    lines = lines[:-1]\n'
            'if len(args) > 1:\n'
            '    open(args[1], "w").writelines(lines)\n'
            'pts = sum(1 for l in open(args[0]) if l.strip())\n'
            'print("SUMMARY code=%s threads=%%d points=%%d tets=%%d read_s=0.001 '
            'tri_s=0.002 peak_rss_kb=1000" %% (t, pts, len(lines)))\n')
            % (frontdt, drop, code))
    os.chmod(path, 0o755)
    return path


def run(runner, args):
    p = subprocess.run([sys.executable, runner] + args, capture_output=True,
                       text=True)
    rows = []
    out = args[args.index('--out') + 1]
    csv_path = os.path.join(out, 'runs.csv')
    if os.path.exists(csv_path):
        with open(csv_path, newline='') as f:
            rows = list(csv.DictReader(f))
    return p, rows


def main(argv):
    if len(argv) not in (5, 6):
        print(__doc__, file=sys.stderr)
        return 1
    runner, frontdt, gen, measure, cgal = argv[:5]
    tetshash = argv[5] if len(argv) == 6 else None
    with tempfile.TemporaryDirectory(prefix='fdt-bench-selftest-') as tmp:
        # An empty --build, so that nothing but the programs named here is
        # found (no peers from some other build folder).
        empty = os.path.join(tmp, 'no-build')
        os.mkdir(empty)
        base = ['--build', empty, '--gen-points', gen, '--measure', measure, '--sizes', '2000',
                '--dist', 'uniform', '--threads', '1,2', '--oversubscribe',
                '--reps', '1', '--no-plots', '--timeout', '120']
        codes = 'frontdt,cgal' if cgal != 'none' else 'frontdt'
        if cgal != 'none':
            base += ['--cmp-cgal', cgal]

        # 1. The real thing.
        out = os.path.join(tmp, 'real')
        p, rows = run(runner, base + ['--frontdt', frontdt, '--codes', codes,
                                      '--modes', 'serial,shared', '--out', out])
        check(p.returncode == 0, 'real run exits 0 (got %d): %s' % (
            p.returncode, p.stderr[-500:]))
        fd = [r for r in rows if r['code'] == 'frontdt']
        check(len(fd) == 3, 'three frontdt rows (serial, shared t1, t2), got %d' % len(fd))
        # A build whose engine refuses shared mode gives 'unavailable' rows.
        for r in fd:
            if r['status'] == 'unavailable':
                continue
            check(r['status'] == 'ok', '%s: status ok, got %s (%s)' % (
                r['config'], r['status'], r['note']))
            want = ('cgal',) if cgal != 'none' else ('ref', 'serial')
            check(r['verdict'] in want, '%s: verdict %s, want %s' % (
                r['config'], r['verdict'], want))
            check(len(r['hash']) == 16, '%s: a 16-digit hash' % r['config'])
            check(float(r['tri_s']) > 0 and float(r['wall_s']) >= float(r['tri_s']),
                  '%s: 0 < tri_s <= wall_s' % r['config'])
            # 2,000 points need a few MiB; forked straight from Python the
            # child would inherit the runner's high-water mark (> 15 MiB).
            check(0 < int(r['peak_rss_kb']) < 15 * 1024,
                  '%s: peak RSS %s KiB is the child\'s own' % (r['config'], r['peak_rss_kb']))
        check(os.path.exists(os.path.join(out, 'summary.md')), 'summary.md written')

        # 2. A wrong answer must never count.
        # Message mode is played by the serial one (so the test does not
        # depend on the engine having it), then reports a wrong hash.
        wrong = wrapper(tmp, 'frontdt_wrong', frontdt, (
            'msg = "message" in argv\n'
            'if msg:\n'
            '    i = argv.index("message")\n'
            '    argv[i] = "serial"\n'
            '    if "-t" in argv:\n'
            '        j = argv.index("-t")\n'
            '        del argv[j:j + 2]\n'
            'r = subprocess.run([real] + argv, capture_output=True, text=True)\n'
            'sys.stderr.write(r.stderr)\n'
            'if msg and r.returncode == 0:\n'
            '    print("hash: 0123456789abcdef")\n'
            'else:\n'
            '    sys.stdout.write(r.stdout)\n'
            'sys.exit(r.returncode)'))
        out = os.path.join(tmp, 'wrong')
        p, rows = run(runner, base + ['--frontdt', wrong, '--codes', codes,
                                      '--modes', 'serial,message', '--out', out])
        check(p.returncode == 3, 'a wrong hash makes the runner exit 3 (got %d): %s'
              % (p.returncode, p.stderr[-500:]))
        msg = [r for r in rows if r['mode'] == 'message']
        check(len(msg) == 2 and all(r['status'] == 'wrong' and r['verdict'] == 'WRONG'
                                    for r in msg),
              'message rows recorded as wrong: %s' % [(r['status'], r['verdict'])
                                                      for r in msg])
        with open(os.path.join(out, 'summary.md')) as f:
            summary = f.read()
        check('| frontdt message t1 | WRONG |' in summary and
              '| frontdt message t2 | WRONG |' in summary,
              'the summary shows WRONG instead of a time')

        # 3. Parallel modes refused by the engine.
        refuse = wrapper(tmp, 'frontdt_serial_only', frontdt, (
            'for m in ("shared", "message"):\n'
            '    if m in argv:\n'
            '        sys.stderr.write("frontdt: cannot use these settings: mode %s '
            'is not available in this build: only serial\\n" % m)\n'
            '        sys.exit(1)\n'
            'sys.exit(subprocess.run([real] + argv).returncode)'))
        out = os.path.join(tmp, 'refuse')
        p, rows = run(runner, base + ['--frontdt', refuse, '--codes', 'frontdt',
                                      '--out', out])
        check(p.returncode == 0, 'refused modes: exit 0 (got %d): %s' % (
            p.returncode, p.stderr[-500:]))
        par = [r for r in rows if r['mode'] in ('shared', 'message')]
        check(len(par) == 4 and all(r['status'] == 'unavailable' for r in par),
              'parallel rows unavailable: %s' % [r['status'] for r in par])
        ser = [r for r in rows if r['mode'] == 'serial']
        check(len(ser) == 1 and ser[0]['status'] == 'ok', 'the serial row still runs')

        if tetshash:
            peers_checks(runner, frontdt, tmp, base, codes, cgal, tetshash)
        else:
            print('no TETSHASH given: the HXT and Geogram checks are skipped')
    if FAILS:
        print('%d check(s) failed' % len(FAILS))
        return 1
    print('bench harness: all checks passed')
    return 0


def peers_checks(runner, frontdt, tmp, base, codes, cgal, tetshash):
    hxt = stand_in_peer(tmp, 'hxt_dt', 'hxt', frontdt, False)
    geo = stand_in_peer(tmp, 'geogram_dt', 'geogram', frontdt, True)
    peer_args = ['--tetshash', tetshash, '--hxt', hxt, '--geogram', geo,
                 '--frontdt', frontdt, '--modes', 'serial',
                 '--codes', codes + ',hxt,geogram']

    # 4. Unique mesh: HXT's tets are checked, Geogram's lost tet is caught.
    out = os.path.join(tmp, 'peers')
    p, rows = run(runner, base + peer_args + ['--out', out])
    check(p.returncode == 0, 'stand-in peers: exit 0, a peer\'s wrong mesh is not '
          'frontdt\'s (got %d): %s' % (p.returncode, p.stderr[-500:]))
    want = 'cgal' if cgal != 'none' else 'serial'
    for code, verdict in (('hxt', want), ('geogram', 'differs (unique mesh)')):
        rs = [r for r in rows if r['code'] == code]
        check(len(rs) == 2 and all(r['status'] == 'ok' and r['verdict'] == verdict
                                   for r in rs),
              '%s t1, t2 on uniform: ok and %r, got %s' % (
                  code, verdict, [(r['config'], r['status'], r['verdict']) for r in rs]))
    for r in rows:
        check(r['status'] != 'ok' or float(r['cpu_s']) > 0,
              '%s: cpu_s recorded' % r['config'])
    fd = [r for r in rows if r['code'] == 'frontdt']
    # a front's rows: what each face cost; the one-part engine's (serial):
    # every tet from the certified mesh, no face advanced
    check(fd and all((float(r['tested_per_face'] or 0) >= 1 and r['exact_per_face'] != '') or
                     (r['final_tets'] != '' and r['final_tets'] == r['tets'])
                     for r in fd),
          'frontdt rows carry tested/exact per face: %s' % [
              (r['tested_per_face'], r['exact_per_face']) for r in fd])
    with open(os.path.join(out, 'summary.md')) as f:
        summary = f.read()
    check('## frontdt beside CGAL, HXT and Geogram' in summary and
          '| / hxt same t | / geogram same t |' in summary,
          'the summary has the four-code table and the HXT, Geogram ratios')

    # 5. Ties broken freely: counts only.
    out = os.path.join(tmp, 'peers-lattice')
    lat = [x if x != 'uniform' else 'lattice' for x in base]
    lat[lat.index('--sizes') + 1] = '512'
    p, rows = run(runner, lat + peer_args + ['--threads', '1', '--out', out])
    got = {r['code']: r['verdict'] for r in rows if r['code'] in ('hxt', 'geogram')}
    check(p.returncode == 0 and got == {'hxt': 'own ties, same count',
                                        'geogram': 'own ties, tets -1'},
          'lattice: peers compared by count (exit %d): %s' % (p.returncode, got))

    # 6. A peer build that makes hxt_dt, then fails.
    src = os.path.join(tmp, 'peers-src')
    os.mkdir(src)
    with open(os.path.join(src, 'build.sh'), 'w') as f:
        f.write('set -e\nmkdir -p "$1"\ncp %s "$1"/hxt_dt\n'
                'echo "geogram: compiler error" >&2\nexit 1\n' % hxt)
    pdir = os.path.join(tmp, 'peers-built')
    built = [x for x in peer_args if x not in ('--hxt', hxt, '--geogram', geo)]
    built += ['--peers-src', src, '--peers-dir', pdir]
    out = os.path.join(tmp, 'peers-build')
    p, rows = run(runner, base + built + ['--out', out])
    st = {r['config']: (r['status'], r['note']) for r in rows
          if r['code'] in ('hxt', 'geogram')}
    check(p.returncode == 0 and st.get('hxt t1', ('',))[0] == 'ok' and
          st.get('geogram t1', ('',))[0] == 'unavailable' and
          'build failed' in st['geogram t1'][1],
          'failed peer build: hxt ok, geogram unavailable with the reason '
          '(exit %d): %s' % (p.returncode, st))
    with open(os.path.join(pdir, 'build.log')) as f:
        check('compiler error' in f.read(), 'the build\'s output is kept in build.log')
    p, rows = run(runner, base + [x if x != codes + ',hxt,geogram' else codes + ',hxt'
                                  for x in built] + ['--out', out + '2'])
    check(p.returncode == 0 and 'building' not in p.stderr and
          any(r['code'] == 'hxt' and r['status'] == 'ok' for r in rows),
          'an up-to-date hxt_dt is reused without a build: %s' % p.stderr[-300:])


if __name__ == '__main__':
    sys.exit(main(sys.argv[1:]))
