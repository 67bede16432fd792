#!/usr/bin/env python3
"""Every figure the documents quote from a committed result set, regenerated and compared (issue 43).

  scripts/claims.py            check: exit 1 and a diff for every generated block that differs
  scripts/claims.py --write    regenerate every block in place (after a new result set: docs/claims.md)
  scripts/claims.py --list     the blocks, their documents and generators
  scripts/claims.py --extract-paper TEX   rewrite results/paper/printed_tables.csv from the paper's LaTeX

A generated block sits between `<!-- claims:begin NAME -->` and `<!-- claims:end NAME -->`; NAME is a
generator of scripts/claim_blocks (GENERATORS), which reads committed result sets only. A block whose
text holds a newline spans lines; otherwise it is a phrase inside a sentence (compared with its
line breaks as spaces, so a paragraph may be reflowed). Also checked: every
generator is quoted somewhere (a deleted block is noticed), the paper's speedups that results/gpu-model/paper_tables.csv
holds are the ones the paper prints, the rtx3060 profile's step_cycles is the fit on Table 2's
committed cells, and the paper's printed figures
(results/paper/printed_tables.csv) are the extraction of its LaTeX when ../shared/reference holds it.
Standard library only; the ctest `claims` runs the check.
"""
import argparse
import difflib
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from claim_blocks import GENERATORS  # noqa: E402
from claim_blocks import gpu_model_scoring, paper_tex  # noqa: E402
from claim_blocks.sets import PAPER_COLUMN, PAPER_SPEEDUPS, ROOT  # noqa: E402

# The documents whose quoted figures are checked (issue 43).
DOCUMENTS = ["results/README.md", "docs/paper.md", "results/gpu-model/README.md"]
BLOCK = re.compile(r"<!-- claims:begin ([\w-]+) -->(.*?)<!-- claims:end ([\w-]+) -->", re.S)


def rendered(name, cache):
    """The block's text as it stands in a document."""
    if name not in cache:
        text = GENERATORS[name]()
        cache[name] = "\n" + text.strip("\n") + "\n" if "\n" in text else text
    return cache[name]


def check_document(rel, write, cache, used):
    """Problems found in one document (with --write: the blocks are rewritten instead)."""
    path = os.path.join(ROOT, rel)
    with open(path, encoding="utf-8") as f:
        text = f.read()
    problems = []

    def one(m):
        name, body, end = m.group(1), m.group(2), m.group(3)
        line = text.count("\n", 0, m.start()) + 1
        if name != end or name not in GENERATORS:
            problems.append(f"claims: {rel}:{line}: block '{name}' (ends '{end}') names no generator of "
                            f"scripts/claim_blocks: use one of {', '.join(sorted(GENERATORS))}")
            return m.group(0)
        used.add(name)
        want = rendered(name, cache)
        if "\n" not in want and " ".join(body.split()) == want:
            return m.group(0)  # a phrase may be wrapped across lines with the paragraph
        if body != want and not write:
            diff = difflib.unified_diff(body.splitlines(), want.splitlines(), "document", "generated", lineterm="", n=0)
            problems.append(f"claims: {rel}:{line}: block '{name}' differs from what its generator computes from the "
                            f"committed sets; fix the text by `scripts/claims.py --write` (or the generator):\n"
                            + "\n".join(diff))
        return m.group(0).replace(body, want, 1) if body else m.group(0).replace("--><!--", f"-->{want}<!--", 1)

    new = BLOCK.sub(one, text)
    if write and new != text:
        with open(path, "w", encoding="utf-8") as f:
            f.write(new)
    return problems


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--write", action="store_true", help="regenerate the blocks in place")
    ap.add_argument("--list", action="store_true", help="list the blocks")
    ap.add_argument("--extract-paper", metavar="TEX", help="rewrite results/paper/printed_tables.csv from TEX")
    a = ap.parse_args()
    if a.extract_paper:
        if not os.path.exists(a.extract_paper):
            sys.exit(f"claims: {a.extract_paper} does not exist: give the paper's LaTeX file")
        with open(a.extract_paper, encoding="utf-8") as f:
            rows = paper_tex.extract(f.read())
        with open(paper_tex.PRINTED, "w", encoding="utf-8") as f:
            f.write(paper_tex.to_csv(rows))
        print(f"claims: {len(rows)} printed figures -> {os.path.relpath(paper_tex.PRINTED, ROOT)}")
        return 0
    cache, used, problems = {}, set(), []
    for rel in DOCUMENTS:
        if a.list:
            with open(os.path.join(ROOT, rel), encoding="utf-8") as f:
                for m in BLOCK.finditer(f.read()):
                    print(f"{rel}: {m.group(1)}")
            continue
        problems += check_document(rel, a.write, cache, used)
    if a.list:
        return 0
    for name in sorted(set(GENERATORS) - used):
        problems.append(f"claims: generator '{name}' is quoted in none of {', '.join(DOCUMENTS)}: "
                        f"put its block back or remove the generator")
    stale = paper_tex.extraction_matches()
    if stale:
        problems.append(f"claims: {stale}: run scripts/claims.py --extract-paper {paper_tex.TEX}")
    wrong = paper_tex.speedups_match(PAPER_SPEEDUPS, PAPER_COLUMN)
    if wrong:
        problems.append(f"claims: {wrong}: fix the CSV (every model comparison reads it)")
    unfitted = gpu_model_scoring.profile_fit_problem()
    if unfitted:
        problems.append(f"claims: {unfitted}: refit it (scripts/gpu_model_validate.py) or say why it differs")
    for p in problems:
        print(p, file=sys.stderr)
    if problems:
        return 1
    print(f"claims: {len(used)} generated blocks in {len(DOCUMENTS)} documents "
          + ("rewritten" if a.write else "match their committed result sets"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
