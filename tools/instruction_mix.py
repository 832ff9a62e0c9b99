"""The instruction mix of spotkin's compiled kernels, per instruction-set clone (objdump).

python tools/instruction_mix.py                      # the dynamics kernels of the built _core
python tools/instruction_mix.py 'rnea_k' 'crba_k'    # functions whose demangled name holds these
python tools/instruction_mix.py --so path/to/_core.so rnea_k

For each matching function (each clone: _avx512, _avx2, _baseline), counts its instructions by
kind: floating-point arithmetic (add, sub, mul, div, sqrt, min, max, fused multiply-add; scalar
or packed), moves (loads, stores, register copies, broadcasts, inserts, extracts), shuffles
(permutes, unpacks, blends), and the rest (integer, compare, branch). A kernel whose hot loop is
dominated by moves spills its packs to memory: its lanes are wider than the level's registers.
This is a static count over the whole function (objdump -d), not a profile: the hot loop is
most of a kernel's body, and the counts compare clones and lane widths like for like.
"""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import sys
from collections import Counter
from pathlib import Path

ARITHMETIC = re.compile(
    r"^v?(add|sub|mul|div|sqrt|min|max|fmadd|fmsub|fnmadd|fnmsub|fmaddsub)\w*(pd|ps|sd|ss)$"
)
MOVES = re.compile(r"^v?(mov\w*|broadcast\w*|insert\w*|extract\w*|gather\w*|lddqu|pinsr\w*|pextr\w*)$")
SHUFFLES = re.compile(r"^v?(perm\w*|shuf\w*|unpck\w*|blend\w*|punpck\w*|pshuf\w*|palignr|valign\w*)$")


def kind(mnemonic: str) -> str:
    if ARITHMETIC.match(mnemonic) or re.match(r"^v?fn?m(add|sub)\d+\w*(pd|ps|sd|ss)$", mnemonic):
        return "arithmetic"
    if MOVES.match(mnemonic):
        return "moves"
    if SHUFFLES.match(mnemonic):
        return "shuffles"
    return "other"


def label(name: str) -> str:
    """A short name: the function, its model's (T, L) and its clone."""
    base = re.sub(r"[(<].*", "", name.replace("(anonymous namespace)::", "")).split("::")[-1]
    model = re.search(r"(\w+Model)<(\w+), (\d+)>", name)
    clone = re.search(r"\[clone \.([\w.]+)\]", name)
    parts = [base]
    if model:
        parts.append(f"{model.group(1)}<{model.group(2)}, {model.group(3)}>")
    if clone:
        parts.append(f"[{clone.group(1)}]")
    return " ".join(parts)


def functions(so: Path, patterns: list[str]) -> dict[str, Counter]:
    """Demangled function name -> Counter of instruction kinds (and 'packed' arithmetic)."""
    text = subprocess.run(
        ["objdump", "-d", "-C", "--no-show-raw-insn", str(so)], capture_output=True, text=True, check=True
    ).stdout
    result: dict[str, Counter] = {}
    current = None
    for line in text.splitlines():
        header = re.match(r"^[0-9a-f]+ <(.*)>:$", line)
        if header:
            name = header.group(1)
            current = label(name) if any(p in name for p in patterns) else None
            if current is not None:
                result.setdefault(current, Counter())
            continue
        if current is None:
            continue
        parts = line.split("\t")
        if len(parts) < 2:
            continue
        mnemonic = parts[1].split()[0] if parts[1].split() else ""
        if not mnemonic:
            continue
        k = kind(mnemonic)
        result[current][k] += 1
        if k == "arithmetic" and mnemonic.endswith(("pd", "ps")):
            result[current]["packed"] += 1
    return result


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("patterns", nargs="*", default=["rnea_k", "crba_k", "aba_k"])
    parser.add_argument("--so", type=Path, help="the extension module (default: the installed spotkin._core)")
    args = parser.parse_args()
    if shutil.which("objdump") is None:
        print("objdump not found: install binutils", file=sys.stderr)
        return 1
    so = args.so
    if so is None:
        import spotkin._core

        so = Path(spotkin._core.__file__)
    rows = functions(so, args.patterns)
    if not rows:
        print(f"no function of {so} matches {args.patterns}", file=sys.stderr)
        return 1
    print(f"{'function':<60}{'instr':>7}{'arith':>7}{'packed':>7}{'moves':>7}{'shuf':>6}{'arith %':>8}")
    for name, c in sorted(rows.items()):
        total = sum(v for k, v in c.items() if k != "packed")
        if total < 50:  # a dispatcher or a resolver
            continue
        short = name if len(name) <= 58 else name[:55] + "..."
        share = 100.0 * c["arithmetic"] / total if total else 0.0
        print(
            f"{short:<60}{total:>7}{c['arithmetic']:>7}{c['packed']:>7}{c['moves']:>7}{c['shuffles']:>6}"
            f"{share:>7.0f}%"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
