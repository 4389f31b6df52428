"""What every benchmark's report page shares: its style sheet and Markdown tables turned into HTML."""

from __future__ import annotations

import html

__all__ = ["PAGE_STYLE", "md_table_to_html"]

#: The style sheet of every report's index.html.
PAGE_STYLE = ("body{font-family:system-ui,sans-serif;margin:2em auto;max-width:1400px;padding:0 1em;line-height:1.45}"
              "table{border-collapse:collapse;font-size:13px;margin:.5em 0}td,th{border:1px solid #ccc;padding:3px 6px;"
              "text-align:center}th{background:#f3f3f3}img{max-width:100%}figure{margin:1.5em 0}"
              "figcaption{font-size:14px;color:#333;max-width:70em}dt{font-weight:600}dd{margin:0 0 .4em 1.5em}"
              ".note{color:#555;font-size:13px}")


def md_table_to_html(md: str) -> str:
    """A Markdown pipe table (and the text lines around it) as HTML."""
    lines = md.splitlines()
    rows = [ln for ln in lines if ln.startswith("|")]
    text = [ln for ln in lines if ln.strip() and not ln.startswith("|")]
    if len(rows) < 2:
        return "".join(f"<p>{html.escape(t.strip('_'))}</p>" for t in text)
    out = ["<table>"]
    for i, ln in enumerate(rows):
        if i == 1:
            continue
        cells = [c.strip() for c in ln.strip("|").split("|")]
        tag = "th" if i == 0 else "td"
        out.append("<tr>" + "".join(
            f"<{tag}>" + (f"<b>{html.escape(c[2:-2])}</b>" if c.startswith("**") else html.escape(c)) + f"</{tag}>"
            for c in cells) + "</tr>")
    out.append("</table>")
    out += [f"<p class='note'>{html.escape(t)}</p>" for t in text]
    return "\n".join(out)
