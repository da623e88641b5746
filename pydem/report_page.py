"""The one page writer of every report (diagnosis, calibration, seed 001): sections as Markdown
and HTML side by side, tables in both, plots as PNG bytes — report.md with the PNG files beside
it, report.html self-contained."""
from __future__ import annotations

import base64
import html
import io
from pathlib import Path


def png(fig) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110, bbox_inches="tight")
    import matplotlib.pyplot as plt
    plt.close(fig)
    return buf.getvalue()


def table(rows: list[list], header: list[str]) -> tuple[str, str]:
    md = "| " + " | ".join(header) + " |\n|" + "---|" * len(header) + "\n"
    md += "".join("| " + " | ".join(map(str, r)) + " |\n" for r in rows)
    h = "<table><tr>" + "".join(f"<th>{html.escape(x)}</th>" for x in header) + "</tr>"
    h += "".join("<tr>" + "".join(f"<td>{html.escape(str(x))}</td>" for x in r) + "</tr>" for r in rows) + "</table>"
    return md, h


def write_page(out: Path, title: str, sections: list[tuple[str, str, str]], plots: dict[str, bytes], head: int) -> Path:
    """report.md (plots as the PNG files beside it) and report.html (self-contained: plots
    embedded after the first `head` sections)."""
    md = f"# {title}\n\n" + "\n\n".join(f"## {t}\n\n{m}" for t, m, _ in sections)
    md += "\n\n## Plots\n\n" + "\n\n".join(f"![{n[:-4]}]({n})" for n in plots) + "\n"
    (out / "report.md").write_text(md)
    imgs = "".join(f"<figure><img alt='{n}' src='data:image/png;base64,{base64.b64encode(p).decode()}'></figure>"
                   for n, p in plots.items())
    page = (f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(title)}</title><style>"
            "body{font-family:sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;overflow-wrap:anywhere}"
            "table{border-collapse:collapse;margin:.5em 0;display:block;overflow-x:auto;max-width:100%}td,th{border:1px solid #ccc;padding:3px 8px;font-size:13px}"
            ".verdict{font-size:1.2em;background:#f4f4f0;padding:.6em}img{max-width:100%}</style></head><body>"
            f"<h1>{html.escape(title)}</h1>" + "".join(f"<h2>{html.escape(t)}</h2>{h}" for t, _, h in sections[:head])
            + imgs + "".join(f"<h2>{html.escape(t)}</h2>{h}" for t, _, h in sections[head:]) + "</body></html>")
    path = out / "report.html"
    path.write_text(page)
    return path
