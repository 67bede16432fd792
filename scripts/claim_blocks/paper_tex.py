"""The paper's printed tables: extracted from its LaTeX into results/paper/printed_tables.csv, and
checked against themselves (a printed speedup against the ratio of its own printed MRays/s; a figure
printed in two tables). The LaTeX is not in the repository; `scripts/claims.py --extract-paper TEX`
rewrites the CSV from it, and the claims check compares the CSV with it whenever
../shared/reference/hierarchy-cut-code-paper.tex is present.
"""
import csv
import io
import os
import re

from .sets import ROOT

PRINTED = os.path.join(ROOT, "results", "paper", "printed_tables.csv")
TEX = os.path.join(ROOT, "..", "shared", "reference", "hierarchy-cut-code-paper.tex")
FIELDS = ["table", "row", "column", "value", "printed_speedup"]

# The paper's row labels, as the suite names the encoders.
ROWS = {"NoSort": "nosort", "HCC (Ours)": "hcc", "MLHCC32 (Ours)": "mlhcc32", "MLHCC16 (Ours)": "mlhcc16",
        "MLHCC (Ours)": "mlhcc", "Regular Grid (Ours)": "grid", "TwoPoint": "twopoint", "Aila_Compact": "aila",
        "Reis": "reis", "Origin": "origin", "PPC": "ppc"}
SCENES = ["Breakfast", "Salle de Bain", "Living room", "Sibenik", "Vokselia", "MultiInstance", "San Miguel",
          "landscape"]
# label in the LaTeX -> (table number, its columns in order)
TABLES = {"tab_Results_Overview": ("2", SCENES),
          "tab_Results_Shadow_Overview": ("3", SCENES),
          "tab_limited_viewport": ("4", SCENES[:4]),
          "tab_overhead": ("5", ["encode ms", "sort ms", "sum ms", "percentage"]),
          "tab_differentBits": ("6", ["16", "32", "64"]),
          "tab_ANC": ("7", ["16", "32", "64"]),
          "tab_HCC_DIR": ("8", ["HCC", "HCC_DIR", "HCC_31bit"])}
NUMBER = re.compile(r"^([0-9.]+)\s*(?:\(([0-9.]+)\))?$")


def _plain(cell):
    """A LaTeX cell without \\textbf{...}, escapes and percent signs."""
    cell = re.sub(r"\\textbf\{(.*)\}", r"\1", cell.strip())
    return cell.replace("\\_", "_").replace("\\%", "").strip()


def extract(tex_text):
    """Every number of the paper's Tables 2-8 as CSV rows (strings exactly as printed), and the
    HCC speedups the limited-viewport figure's caption prints (table '4-caption')."""
    rows = []
    for label, (table, columns) in TABLES.items():
        start = tex_text.index("\\label{%s}" % label)
        body = tex_text[start:tex_text.index("\\end{tabular}", start)]
        for line in body.split("\\\\"):
            cells = [_plain(c) for c in line.replace("\\hline", "").split("&")]
            if len(cells) != len(columns) + 1 or not all(NUMBER.match(c) for c in cells[1:]):
                continue
            name = ROWS.get(cells[0], cells[0])
            for column, cell in zip(columns, cells[1:]):
                value, speedup = NUMBER.match(cell).groups()
                rows.append({"table": table, "row": name, "column": column, "value": value,
                             "printed_speedup": speedup or ""})
    caption = re.search(r"The speedup ratio of hierarchy cut code in these scenes are: (.*?)\}", tex_text)
    for value, scene in re.findall(r"\([a-d]\) ([0-9.]+) in ([A-Za-z ]+?)(?:,|\.)", caption.group(1)):
        rows.append({"table": "4-caption", "row": "hcc", "column": scene.strip(), "value": "",
                     "printed_speedup": value})
    return rows


def to_csv(rows):
    out = io.StringIO()
    w = csv.DictWriter(out, FIELDS, lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
    return out.getvalue()


def printed():
    with open(PRINTED, newline="") as f:
        return list(csv.DictReader(f))


def _half_unit(text):
    """Half a unit of the last printed digit: 37.0 -> 0.05, 0.0464 -> 0.00005."""
    return 0.5 * 10 ** -(len(text.split(".")[1]) if "." in text else 0)


def ratio_interval(value, base):
    """Every ratio the unrounded figures behind two printed figures can have."""
    v, b = float(value), float(base)
    hv, hb = _half_unit(value), _half_unit(base)
    return (v - hv) / (b + hb), (v + hv) / (b - hb)


def speedup_contradictions(rows):
    """Printed speedups of Tables 2-4 that no unrounded MRays/s behind the printed ones can give."""
    nosort = {(r["table"], r["column"]): r["value"] for r in rows if r["row"] == "nosort"}
    checked, bad = 0, []
    for r in rows:
        if r["table"] not in ("2", "3", "4") or r["row"] == "nosort" or not r["printed_speedup"]:
            continue
        checked += 1
        lo, hi = ratio_interval(r["value"], nosort[(r["table"], r["column"])])
        h = _half_unit(r["printed_speedup"])
        if not lo - h <= float(r["printed_speedup"]) <= hi + h:
            bad.append((r, nosort[(r["table"], r["column"])], float(r["value"]) / float(nosort[(r["table"], r["column"])])))
    return checked, bad


# A figure printed twice: (table, row, column) pairs that must carry the same number.
SAME_FIGURE = ([(("6", enc6, "32"), ("2", enc2, "Sibenik"))
                for enc6, enc2 in (("hcc", "hcc"), ("mlhcc", "mlhcc32"), ("twopoint", "twopoint"), ("ppc", "ppc"))]
               + [(("8", scene, "HCC"), ("2", "hcc", scene))
                  for scene in ("Breakfast", "Salle de Bain", "Living room", "Sibenik", "Vokselia")])


def repeated_contradictions(rows):
    """Figures printed in two places with different values; the caption's HCC speedups against Table 4."""
    at = {(r["table"], r["row"], r["column"]): r for r in rows}
    checked, bad = 0, []
    for a, b in SAME_FIGURE:
        checked += 1
        if float(at[a]["value"]) != float(at[b]["value"]):
            bad.append((a, at[a]["value"], b, at[b]["value"]))
    for r in (r for r in rows if r["table"] == "4-caption"):
        checked += 1
        t4 = at[("4", "hcc", r["column"])]
        if r["printed_speedup"] != t4["printed_speedup"]:
            bad.append((("4-caption", "hcc", r["column"]), r["printed_speedup"], ("4", "hcc", r["column"]),
                        t4["printed_speedup"]))
    for enc in sorted({r["row"] for r in rows if r["table"] == "5"}):
        checked += 1
        v = {c: at[("5", enc, c)]["value"] for c in ("encode ms", "sort ms", "sum ms")}
        if abs(float(v["encode ms"]) + float(v["sort ms"]) - float(v["sum ms"])) > 0.011:
            bad.append((("5", enc, "sum ms"), v["sum ms"], ("5", enc, "encode + sort"),
                        f"{float(v['encode ms']) + float(v['sort ms']):.2f}"))
    return checked, bad


def _where(key):
    table, row, column = key
    name = "the Table 4 figure's caption" if table == "4-caption" else f"Table {table}"
    return f"{name}, {row}, {column}" + (" bits" if table in ("6", "7") else "")


def inconsistencies_block():
    """docs/paper.md: the paper's own contradictions, recomputed from its printed figures."""
    rows = printed()
    n_speed, bad_speed = speedup_contradictions(rows)
    n_same, bad_same = repeated_contradictions(rows)
    out = [f"Checked: {n_speed} printed speedups of Tables 2, 3 and 4 against the ratio of their own printed "
           f"MRays/s to NoSort's (any unrounded figures that round to the printed ones), {n_same} figures printed "
           f"twice (Table 6's 32-bit row against Table 2's Sibenik column, Table 8's HCC column against Table 2, "
           f"the Table 4 figure's caption against Table 4, Table 5's sums). Contradictions:", "",
           "| where | printed | from the paper's own figures | how far |", "|---|---|---|---|"]
    for r, base, ratio in bad_speed:
        # one unit off in the last digit (1.609 printed 1.60) is a rounding slip, not a contradiction
        slip = abs(float(r["printed_speedup"]) - ratio) < 3 * _half_unit(r["printed_speedup"])
        out.append(f"| Table {r['table']}, {r['row']}, {r['column']} | speedup {r['printed_speedup']} | "
                   f"{r['value']} / {base} MRays/s = {ratio:.3f} | "
                   + ("one unit in the last digit" if slip else "**contradiction**") + " |")
    for a, va, b, vb in bad_same:
        out.append(f"| {_where(a)} | {va} | {_where(b)}: {vb} | **contradiction** |")
    return "\n".join(out)


def extraction_matches():
    """None when the LaTeX is absent or the committed CSV is its extraction; else what differs."""
    if not os.path.exists(TEX):
        return None
    with open(TEX, encoding="utf-8") as f:
        fresh = to_csv(extract(f.read()))
    with open(PRINTED, encoding="utf-8") as f:
        committed = f.read()
    return None if fresh == committed else f"{os.path.relpath(PRINTED, ROOT)} is not the extraction of {TEX}"


def speedups_match(paper_speedups_csv, column_of):
    """None when every speedup of results/gpu-model/paper_tables.csv is the paper's printed one (Tables 2
    and 3: the figure in parentheses, to the CSV's digits; Table 6: its MRays/s over Table 2's NoSort on
    Sibenik); else the first that is not."""
    at = {(r["table"], r["row"], r["column"]): r for r in printed()}
    with open(paper_speedups_csv, newline="") as f:
        for r in csv.DictReader(f):
            row = "mlhcc32" if r["encoder"] == "mlhcc" and r["table"] != "6" else r["encoder"]
            digits = len(r["paper_speedup"].split(".")[1])
            if r["table"] == "6":
                want = float(at[("6", row, r["bits"])]["value"]) / float(at[("2", "nosort", "Sibenik")]["value"])
            else:
                want = float(at[(r["table"], row, column_of[r["scene"]])]["printed_speedup"])
            if f"{want:.{digits}f}" != r["paper_speedup"]:
                return (f"{os.path.relpath(paper_speedups_csv, ROOT)}: Table {r['table']} {r['scene']} {r['encoder']} "
                        f"{r['bits']} bits is {r['paper_speedup']}, the paper prints {want:.{digits}f}")
    return None
