"""Mutation testing: small deliberate bugs in a copy of the formula writer, each of which must be
caught by `linkbook verify` (on the bundled books and on books aimed at it) and by the tests.

    python tests/mutants.py                 # every mutant: verify, then the fast tests
    python tests/mutants.py --only sign     # mutants whose name contains "sign"
    python tests/mutants.py --no-tests      # verify only (a minute a mutant)

Each mutant is one text substitution in a copy of the repository (src/, templates/, tests/ and
docs/; nothing beside it). "verify" is caught when a build fails or any verify exits
non-zero; "tests" when the fast test files fail. The table at the end is the closing note's.
"""
from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FORCES = "tests/data/forces"      # the templates with masses and loads the force mutants aim at
BUNDLED = sorted(p.stem for p in (ROOT / "templates").glob("*.toml"))
SYNTHESIS_TESTS = ["tests/test_synthesis_book.py", "tests/test_synthesis_drawing.py"]
DYADS_TESTS = ["tests/test_synthesis_dyads_book.py"]
FAST_TESTS = ["tests/test_verdict.py", "tests/test_published.py", "tests/test_motion.py",
              "tests/test_language.py", "tests/test_forces_book.py",
              "tests/test_slotted_forces.py"]
NON_GRASHOF = ["--set", "a1=100", "--set", "a2=60", "--set", "a3=50", "--set", "a4=40"]
DEAD_CENTRE = ["--set", "a1=10", "--set", "a2=20", "--set", "a3=4", "--set", "a4=6",
               "--set", "b3=3", "--set", "c3=2", "--step", "10"]
TRIAD = [("triad-sixbar", [])]      # the triad's mutants: the bundled triad six-bar
TRIAD_FORCES = [(f"{FORCES}/triad-sixbar.toml", [])]  # its forces' mutants: it with masses
NEAR_CHANGE_POINT = ["--set", "a4=42.69"]       # s + l exceeds p + q by 1e-4 of it
RAM_DEAD_CENTRE = ["--set", "a4=100", "--set", "a5=300", "--set", "b1=-190"]
# A Jansen leg whose knee angles (θ of the links p and q at C) reach below -180° in radians, out
# of every allowed window unless the degree view wraps them: the bundled books' degree views
# already fall in the window of their windowed ATAN2 radians.
WIDE_KNEE = [f"--set={s}" for s in ("m=20.717", "a=38.0", "l=7.8", "j=94.462", "b=25.522",
                                    "k=82.043", "c=53.014", "d=77.328", "e=58.441", "f=37.167",
                                    "g=47.763", "h=44.116", "i=90.412")]


@dataclass
class Mutant:
    name: str
    path: str                   # relative to the repository
    old: str
    new: str
    books: list = field(default_factory=list)   # (template, extra build arguments) aimed at it
    # verify only the books aimed at it: a mutant whose term vanishes at their inputs (and not
    # at every bundled book's), which verify must catch at its other input sets
    aimed_only: bool = False
    # test files aimed at it, run after FAST_TESTS (which hold none of the synthesis tests)
    tests: list = field(default_factory=list)


MUTANTS = [
    Mutant("triad: a sign of its Jacobian (J12 negated)", "src/linkbook/language/steps/triad.py",
           'f"{_p(cross(v, u))}/{ln}", f"iteration {k}: ∂r{i}/∂{w}")',
           'f"{\'-\' if (i, j) == (1, 2) else \'\'}{_p(cross(v, u))}/{ln}", '
           'f"iteration {k}: ∂r{i}/∂{w}")', TRIAD, aimed_only=True),
    Mutant("triad: one Newton iteration fewer than the step writes",
           "src/linkbook/language/steps/triad.py",
           "for k in range(self.iterations):", "for k in range(self.iterations - 1):", TRIAD,
           aimed_only=True),
    Mutant("triad: its first guess in the other assembly (φ from the sketch turned half a turn)",
           "src/linkbook/language/steps/triad.py",
           'f"ATAN2(({sx0})-({px}),({sy0})-({py})))"', 'f"ATAN2(({px})-({sx0}),({py})-({sy0})))"',
           TRIAD, aimed_only=True),
    Mutant("triad force: the sign of a binary link's force across it (g_k) flipped",
           "src/linkbook/language/steps/triad.py",
           'text = f"{_p(w.moment(link, pivot))}/({{{TO_METRES}}}*{length})"',
           'text = f"-{_p(w.moment(link, pivot))}/({{{TO_METRES}}}*{length})"',
           TRIAD_FORCES, aimed_only=True, tests=["tests/test_triad_forces.py"]),
    Mutant("triad force: the ternary's known loads' moment taken about N1, its arms from N0",
           "src/linkbook/language/steps/triad.py",
           "w.resultant(ternary), w.moment(ternary, points[0])",
           "w.resultant(ternary), w.moment(ternary, points[1])",
           TRIAD_FORCES, aimed_only=True, tests=["tests/test_triad_forces.py"]),
    Mutant("sign: a dyad's output angle ϕ + ψ for ϕ − ψ", "src/linkbook/language/steps/dyad.py",
           'f"{{{angle}}}-{{{branch}}}*{{{psi.key}}}{q_offset}"',
           'f"{{{angle}}}+{{{branch}}}*{{{psi.key}}}{q_offset}"'),
    Mutant("branch: the slider's assembly branch flipped",
           "src/linkbook/language/steps/slider.py",
           'f"{turn}PI()/2+{{{branch}}}*(PI()/2-"', 'f"{turn}PI()/2-{{{branch}}}*(PI()/2-"'),
    Mutant("guard: the cosine rule's ACOS without its guard (#NUM! for #N/A)",
           "src/linkbook/language/excel.py",
           'return f"IFERROR(IF({fails},NA(),ACOS({cosine})),NA())"',
           'return f"ACOS({cosine})"', [("fourbar", NON_GRASHOF)]),
    Mutant("constant: the input angle off by 1e-9", "src/linkbook/language/columns.py",
           'f"RADIANS({{{key}_deg}})"', 'f"RADIANS({{{key}_deg}})*(1+1E-9)"'),
    Mutant("drawing: every link's rows drawn from its first joint", "src/linkbook/book/joints.py",
           'set_formula(ws[f"{x_col}{row}"], f"={cells[name][0]}")',
           'set_formula(ws[f"{x_col}{row}"], f"={cells[link[0]][0]}")'),
    Mutant("drawing: the last link ends at the first link's first point",
           "src/linkbook/language/presentation.py",
           "        used = list(dict.fromkeys(n for link in m.links for n in link))",
           "        m.links[-1] = m.links[-1][:-1] + (m.links[0][0],)\n"
           "        used = list(dict.fromkeys(n for link in m.links for n in link))"),
    Mutant("guard: a rate's dead-centre test dropped (#DIV/0! for #N/A)",
           "src/linkbook/language/excel.py",
           'return f"IF({den}=0,NA(),{_p(num)}/{_p(den)})"', 'return f"{_p(num)}/{_p(den)}"',
           [("fourbar", DEAD_CENTRE)]),
    Mutant("constant: the Grashof threshold 1e-12 made 1e-3", "src/linkbook/book/summary.py",
           "{others}*(1+1E-12)", "{others}*(1+1E-3)", [("fourbar", NEAR_CHANGE_POINT)]),
    Mutant("condition: the quick-return ratio without its (a4 - a5) dead-centre test",
           "templates/quick-return.toml",
           "+ IFERROR((b1/(a4-a5)>=COS(alpha))*(b1/(a4-a5)<=1),0),", ",",
           [("quick-return", RAM_DEAD_CENTRE)]),
    Mutant("sampling: the stroke sheet 10 times coarser", "src/linkbook/book/stroke.py",
           "    step = t.stroke_step\n", "    step = t.stroke_step * 10\n",
           [("pump", ["--step", "5"])]),
    Mutant("window: a degree view without its 360° window", "src/linkbook/book/sweep.py",
           'return f"=MOD(DEGREES({ref}){shift},360){back}"', 'return f"=DEGREES({ref})"',
           [("jansen", WIDE_KNEE)]),
    Mutant("frame: the drawing's centre y from x max", "src/linkbook/book/frames.py",
           "\"cy\": f\"=({ref['ymin']}+{ref['ymax']})/2\"",
           "\"cy\": f\"=({ref['ymin']}+{ref['xmax']})/2\""),
    Mutant("frame: the margin left out of the grid square", "src/linkbook/book/frames.py",
           '            f"*{MARGIN}/{2 * HALF}",', '            f"/{2 * HALF}",'),
    Mutant("frame: y mapped from the x centre", "src/linkbook/book/frames.py",
           'centre = ref["cx"] if axis == "x" else ref["cy"]', 'centre = ref["cx"]'),
    Mutant("frame: a numbers-only copy keeps the #N/A (the extents become #N/A)",
           "src/linkbook/book/style.py",
           """value = f'=IF(ISNUMBER({src}),{src},"{DASH}")' if src""",
           """value = f'={src}' if src""", [("fourbar", NON_GRASHOF)]),
    Mutant("frame: the grid square's legend one decimal short", "src/linkbook/book/frames.py",
           'decimals = f"MAX(0,-INT(ROUND(LOG10({text}),6)))"',
           'decimals = f"MAX(0,-INT(ROUND(LOG10({text}),6))-1)"'),
    Mutant("force sign: a reaction's x component with the link's resultant's sign flipped",
           "src/linkbook/language/forces.py",
           "self.outer(f, of, lin((1, x), (-1, ffx)), lin((1, y), (-1, ffy)), where)",
           "self.outer(f, of, lin((1, x), (1, ffx)), lin((1, y), (-1, ffy)), where)",
           [(f"{FORCES}/fourbar.toml", []), (f"{FORCES}/toggle-press.toml", [])]),
    Mutant("force centre: a centre of mass placed by distance on the wrong side",
           "src/linkbook/language/bodies.py",
           'x, y = plus(axp, f"{d}*COS({t})"), plus(ayp, f"{d}*SIN({t})")',
           'x, y = plus(axp, f"-{d}*COS({t})"), plus(ayp, f"-{d}*SIN({t})")',
           [(f"{FORCES}/marghitu.toml", []), (f"{FORCES}/slider-crank.toml", [])]),
    Mutant("force inertia: a link's inertia torque −I·α left out",
           "src/linkbook/language/bodies.py",
           "                body.couples.append(lin((-1, mul(inertia, alpha))))\n",
           "                pass\n",
           [(f"{FORCES}/fourbar.toml", ["--set", "alpha_in=50"]),
            (f"{FORCES}/watt-sixbar.toml", [])]),
    Mutant("force friction sign: a torque load written with its sign flipped (the four-bar's "
           "friction −T4·SIGN(ω14) drives its rocker)",
           "src/linkbook/language/bodies.py",
           'body.couples.append(self.expr(f"{where}.torque", load["torque"]))',
           'body.couples.append(lin((-1, self.expr(f"{where}.torque", load["torque"]))))',
           [("fourbar", [])]),
    Mutant("force column: a pin force's size not written",
           "src/linkbook/language/forces.py",
           'self.add(key, key, NEWTON, f"SQRT({sq(x)}+{sq(y)})", f"{what}, size", (2, pair))',
           "pass"),
    Mutant("force slide: a block's couple dropped from its turning guide's moments (a slide's "
           "link, a slotted link)",
           "src/linkbook/language/steps/slide.py",
           """guard(det, lin((1, w.moment(link, pivot)),
                                                      (1, w.moment(blk, p)))))""",
           """guard(det, lin((1, w.moment(link, pivot)))))""",
           [(f"{FORCES}/inverted-slider-crank.toml", []),
            (f"{FORCES}/quick-return.toml", ["--set", "I_blk=0.01"])]),
    Mutant("force slotted centre: a slotted link's centre of mass on the wrong side (its frame, "
           "pivot to pin, turned half a turn)",
           "src/linkbook/language/bodies.py",
           '        theta = self._frame_angle(f"{where}.centre.frame", name, a, b)\n',
           '        theta = self._frame_angle(f"{where}.centre.frame", name, a, b)\n'
           '        if body.frames:\n'
           '            theta = Expr(f"{theta.at_least(SUM)}+PI()", SUM)\n',
           [(f"{FORCES}/quick-return.toml", []), (f"{FORCES}/shaper.toml", [])]),
    Mutant("force slot: the slot's push on the plunger across the line, not across the slot",
           "src/linkbook/language/steps/slot.py",
           "mx, my = w.neg(mul(uy, lam)), mul(ux, lam)",
           "mx, my = w.neg(mul(ey, lam)), mul(ex, lam)",
           [(f"{FORCES}/pump.toml", [])]),
    Mutant("force block: a block on a moving guide does not turn (its inertia torque left out)",
           "src/linkbook/language/bodies.py",
           "if inertia != ZERO and (not body.block or body.spin is not None):",
           "if inertia != ZERO and not body.block:",
           [(f"{FORCES}/rocker-block.toml", ["--set", "I6=0.01"])]),
    Mutant("force gravity: the default direction up (+90°), not down",
           "src/linkbook/language/bodies.py",
           'spec.get("angle", -90)', 'spec.get("angle", 90)',
           [(f"{FORCES}/marghitu.toml", [])]),
    # The Synthesis sheet (function generation): aimed at the bundled synthesis book
    Mutant("synthesis sign: K2's column cos θ2 for −cos θ2", "src/linkbook/book/synthesis.py",
           """"m2": f"=-COS({c['theta2']})\"""", """"m2": f"=COS({c['theta2']})\"""",
           [("function-log10", [])], aimed_only=True, tests=SYNTHESIS_TESTS),
    Mutant("synthesis chebyshev: the cosine's argument (2j + 1)π/(2n) for (2j − 1)π/(2n)",
           "src/linkbook/book/synthesis.py", "*COS((2*{c['j']}-1)*PI()/(2*{n}))",
           "*COS((2*{c['j']}+1)*PI()/(2*{n}))", [("function-log10", [])], aimed_only=True,
           tests=SYNTHESIS_TESTS),
    Mutant("synthesis branch: the branch at each precision point inverted",
           "src/linkbook/book/synthesis.py", "0,SIGN({c['cross']}))", "0,-SIGN({c['cross']}))",
           [("function-log10", [])], aimed_only=True, tests=SYNTHESIS_TESTS),
    Mutant("synthesis lengths: the crank and the rocker swapped (a = d/K2, c = d/K1)",
           "src/linkbook/book/synthesis.py", '"=IF(syn_K1=0,NA(),syn_d/syn_K1)"',
           '"=IF(syn_K2=0,NA(),syn_d/syn_K2)"', [("function-log10", [])], aimed_only=True,
           tests=SYNTHESIS_TESTS),
    # vanishes at the bundled task's x0 = 1: caught only where verify's other input set moves
    # the task (input_sets.py)
    Mutant("synthesis vanishing: the Chebyshev points' centre from x0² (x0 = 1 in the book)",
           "src/linkbook/book/synthesis.py", 'f"=(syn_x0+syn_x1)/2-(syn_x1-syn_x0)/2"',
           'f"=(syn_x0^2+syn_x1)/2-(syn_x1-syn_x0)/2"', [("function-log10", [])],
           aimed_only=True, tests=SYNTHESIS_TESTS),
    Mutant("synthesis drawing: each position's joints at the next precision angle",
           "src/linkbook/book/synthesis_drawing.py",
           "resolve = Resolver(model, names, {t.mechanism.input_column: angle})",
           "resolve = Resolver(model, names, {t.mechanism.input_column: angles[i % len(angles)]})",
           [("function-log10", []), ("motion-3pose", [])], aimed_only=True,
           tests=SYNTHESIS_TESTS + DYADS_TESTS),
    # The Synthesis sheet (motion and path generation): aimed at the bundled synthesis books
    Mutant("synthesis dyads swapped: the free choices β2 and γ2 swapped in the pose table",
           "src/linkbook/book/synthesis_dyads.py",
           '''"beta": f"=syn_beta{j}" if j > 1 else "=0",
                    "gamma": f"=syn_gamma{j}" if j > 1 else "=0",''',
           '''"beta": f"=syn_{'gamma' if j == 2 else 'beta'}{j}" if j > 1 else "=0",
                    "gamma": f"=syn_{'beta' if j == 2 else 'gamma'}{j}" if j > 1 else "=0",''',
           [("motion-3pose", []), ("path-timing", [])], aimed_only=True, tests=DYADS_TESTS),
    Mutant("synthesis dyads sign: B_j's imaginary part −sin β_j for sin β_j",
           "src/linkbook/book/synthesis_dyads.py",
           '''            formulas[f"{part}_im"] = f"=SIN(RADIANS({c[angle]}))"''',
           '''            formulas[f"{part}_im"] = f"=SIN(RADIANS({c[angle]}))" if part != "b" \\
                else f"=-SIN(RADIANS({c[angle]}))"''',
           [("motion-3pose", []), ("path-timing", [])], aimed_only=True, tests=DYADS_TESTS),
    Mutant("synthesis dyads branch: the branch at each pose inverted",
           "src/linkbook/book/synthesis_dyads.py", "SIGN({c['cross']}))\",",
           "-SIGN({c['cross']}))\",", [("motion-3pose", []), ("path-timing", [])],
           aimed_only=True, tests=DYADS_TESTS),
    # Terms that vanish at the books' own inputs: caught only at verify's other input sets
    Mutant("vanishing: the crank's inertia torque −I·α left out (α = alpha_in = 0)",
           "src/linkbook/language/bodies.py",
           "                body.couples.append(lin((-1, mul(inertia, alpha))))\n",
           '                if alpha != "{alpha_in}":\n'
           "                    body.couples.append(lin((-1, mul(inertia, alpha))))\n",
           [("fourbar", []), ("slider-crank", []), ("pump", [])], aimed_only=True),
    Mutant("vanishing: a slider's offset left out of its loop (offset a1 = 0)",
           "src/linkbook/language/steps/slider.py",
           "slider(c.model, pin_x=dx.text, pin_y=dy.at_least(PRODUCT), line_y=\"0\",",
           "slider(c.model, pin_x=dx.text, pin_y=py.at_least(PRODUCT), line_y=\"0\",",
           [("slider-crank", ["--set", "a1=0"])], aimed_only=True),
    Mutant("vanishing: the weight m·g left out (g = 0)",
           "src/linkbook/language/bodies.py",
           "            wx = lin((1, mul(mass, g[0])), (-1, mul(mass, METRES_REF, ax)))\n"
           "            wy = lin((1, mul(mass, g[1])), (-1, mul(mass, METRES_REF, ay)))\n",
           "            wx = lin((-1, mul(mass, METRES_REF, ax)))\n"
           "            wy = lin((-1, mul(mass, METRES_REF, ay)))\n",
           [("fourbar", ["--set", "g=0"]), ("slider-crank", ["--set", "g=0"])],
           aimed_only=True),
]


def copy_repository(dest: Path) -> Path:
    repo = dest / "linkbook"
    for part in ("src", "templates", "tests", "docs"):
        shutil.copytree(ROOT / part, repo / part,
                        ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    return repo


def apply(repo: Path, m: Mutant) -> None:
    path = repo / m.path
    text = path.read_text(encoding="utf-8")
    if text.count(m.old) != 1:
        raise SystemExit(f"mutant {m.name!r}: the text to change occurs {text.count(m.old)} "
                         f"times in {m.path} (must be once)")
    path.write_text(text.replace(m.old, m.new), encoding="utf-8")


def run(repo: Path, args: list[str], timeout: int = 900) -> int:
    env = {**os.environ, "PYTHONPATH": str(repo / "src"), "TQDM_DISABLE": "1"}
    proc = subprocess.run(args, cwd=repo, env=env, capture_output=True, text=True,
                          timeout=timeout)
    return proc.returncode


def caught_by_verify(repo: Path, m: Mutant, work: Path) -> str:
    books = ([] if m.aimed_only else [(name, []) for name in BUNDLED]) + m.books
    for i, (name, extra) in enumerate(books):
        book = work / f"{i}-{Path(name).stem}.xlsx"     # a name may be a path
        if run(repo, [sys.executable, "-m", "linkbook", "build", name, *extra, "-o",
                      str(book)]) != 0:
            return f"build of {name} {' '.join(extra)} failed"
        if run(repo, [sys.executable, "-m", "linkbook", "verify", str(book)]) != 0:
            return f"{name} {' '.join(extra)}".strip()
    return ""


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", default="", help="run the mutants whose name contains this")
    ap.add_argument("--no-tests", action="store_true", help="verify only")
    opts = ap.parse_args()
    rows = []
    for m in MUTANTS:
        if opts.only not in m.name:
            continue
        start = time.perf_counter()
        with tempfile.TemporaryDirectory(prefix="linkbook-mutant-") as tmp:
            repo = copy_repository(Path(tmp))
            apply(repo, m)
            work = Path(tmp) / "books"
            work.mkdir()
            by_verify = caught_by_verify(repo, m, work)
            by_tests = "" if opts.no_tests else (
                "failed" if run(repo, [sys.executable, "-m", "pytest", "-x", "-q",
                                       "-p", "no:cacheprovider", *m.tests, *FAST_TESTS],
                                timeout=1800) != 0 else "")
        rows.append((m.name, by_verify, by_tests, time.perf_counter() - start))
        print(f"{m.name}: verify {'caught (' + by_verify + ')' if by_verify else 'MISSED'}"
              f"{'' if opts.no_tests else ', tests ' + ('caught' if by_tests else 'MISSED')}",
              flush=True)
    print()
    print(f"{'mutant':72} {'verify':8} {'tests':8}")
    for name, v, t, _ in rows:
        print(f"{name:72} {'caught' if v else 'MISSED':8} "
              f"{'-' if opts.no_tests else 'caught' if t else 'MISSED':8}")
    survivors = [r for r in rows if not r[1] or (not opts.no_tests and not r[2])]
    print(f"\n{len(rows) - len(survivors)} of {len(rows)} mutants caught")
    return 1 if survivors else 0


if __name__ == "__main__":
    sys.exit(main())
