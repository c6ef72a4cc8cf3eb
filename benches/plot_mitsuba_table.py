#!/usr/bin/env python3
"""Draws docs/mitsuba-comparison.svg from the Mitsuba table in docs/performance.md.

Reads the rows `| scene | renderer | Msamples/s | ... |` of the table under
"## Against Mitsuba 3" and writes one horizontal bar per renderer, grouped by
scene: samples per second, longer is faster. Standard library only; the SVG
is written by hand, so the plot's numbers are the document's.

    python3 benches/plot_mitsuba_table.py            # writes docs/mitsuba-comparison.svg
"""
import html
import pathlib
import re
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
DOC = ROOT / "docs" / "performance.md"
OUT = ROOT / "docs" / "mitsuba-comparison.svg"


def table_rows(text):
    """(scene, renderer, Msamples/s) of the table under '## Against Mitsuba 3'."""
    section = text.split("## Against Mitsuba 3", 1)[1].split("\n## ", 1)[0]
    rows = []
    for line in section.splitlines():
        cells = [c.strip().strip("*") for c in line.strip().strip("|").split("|")]
        if len(cells) != 5 or not re.fullmatch(r"[0-9.]+", cells[2]):
            continue
        rows.append((cells[0], cells[1], float(cells[2])))
    return rows


def colour(renderer):
    if renderer.startswith("Mitsuba"):
        return "#8c8c8c"
    if "CPU" in renderer:
        return "#1f77b4"
    return "#ff7f0e"


def svg(rows, commit):
    left, bar_max, row_h, top = 250, 330, 18, 40
    scenes = []
    for scene, _, _ in rows:
        if scene not in scenes:
            scenes.append(scene)
    height = top + len(rows) * row_h + len(scenes) * 24 + 30
    width = left + bar_max + 70
    top_value = max(v for _, _, v in rows)
    out = [
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
        f'viewBox="0 0 {width} {height}" font-family="sans-serif" font-size="12">',
        f'<rect width="{width}" height="{height}" fill="white"/>',
        f'<text x="10" y="20" font-size="14" font-weight="bold">Msamples/s, 256×256, '
        f'2 cores (longer is faster; at {html.escape(commit)})</text>',
    ]
    y = top
    for scene in scenes:
        out.append(f'<text x="10" y="{y + 12}" font-weight="bold">{html.escape(scene)}</text>')
        y += 20
        for s, renderer, value in rows:
            if s != scene:
                continue
            w = bar_max * value / top_value
            out.append(f'<text x="{left - 6}" y="{y + 12}" text-anchor="end">'
                       f'{html.escape(renderer)}</text>')
            out.append(f'<rect x="{left}" y="{y + 2}" width="{w:.1f}" height="{row_h - 5}" '
                       f'fill="{colour(renderer)}"/>')
            out.append(f'<text x="{left + w + 4:.1f}" y="{y + 12}">{value:.3f}</text>')
            y += row_h
        y += 4
    out.append(f'<text x="10" y="{height - 10}" fill="#555">grey: Mitsuba 3.9.1; '
               f'blue: vkpt CPU back end; orange: vkpt on lavapipe</text>')
    out.append("</svg>")
    return "\n".join(out) + "\n"


def main():
    text = DOC.read_text(encoding="utf-8")
    rows = table_rows(text)
    if not rows:
        sys.exit(f"no table rows found in {DOC}")
    section = text.split("## Against Mitsuba 3", 1)[1]
    commit = re.search(r"at\s+commit\s+([0-9a-f]{7,40})", section)
    OUT.write_text(svg(rows, commit.group(1) if commit else "?"), encoding="utf-8")
    print(f"wrote {OUT.relative_to(ROOT)} ({len(rows)} bars)")


if __name__ == "__main__":
    main()
