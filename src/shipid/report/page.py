"""The page every shipid report shares: its style sheet and its HTML shell.

Self-contained: inline CSS, no JavaScript, nothing fetched from the network. Used by the report of a
:class:`~shipid.result.Result` (:mod:`shipid.report.html`) and by the monitor's report, so that both
read the same.
"""

from __future__ import annotations

import html

import shipid

CSS = """
:root{--ink:#1d2330;--muted:#5b6474;--line:#d9dde5;--soft:#f4f6f9;--accent:#1f6fb4;--bad:#b3261e;--ok:#1e7a46;}
*{box-sizing:border-box}
html{font-size:15px}
body{margin:0;color:var(--ink);background:#fff;font-family:"Source Sans Pro","Segoe UI",Roboto,"Helvetica Neue",
 Arial,sans-serif;line-height:1.45}
main{max-width:1020px;margin:0 auto;padding:24px 28px 60px}
header.top{border-bottom:3px solid var(--accent);padding-bottom:12px;margin-bottom:8px}
header.top h1{font-size:1.65rem;margin:0 0 2px;font-weight:600;letter-spacing:-.01em}
header.top .sub{color:var(--muted);font-size:.98rem}
h2{font-size:1.22rem;margin:34px 0 10px;padding-bottom:4px;border-bottom:1px solid var(--line);font-weight:600}
h3{font-size:1.02rem;margin:22px 0 8px;font-weight:600;color:#2b3445}
p{margin:6px 0}
.small{font-size:.86rem;color:var(--muted)}
nav.toc{font-size:.88rem;color:var(--muted);margin:10px 0 4px}
nav.toc a{color:var(--accent);text-decoration:none;margin-right:14px;white-space:nowrap}
.badges{display:flex;flex-wrap:wrap;gap:8px;margin:14px 0 6px}
.badge{border:1px solid var(--line);border-radius:6px;padding:6px 12px;background:var(--soft);font-size:.9rem}
.badge b{display:block;font-size:1.05rem}
.badge.ok b{color:var(--ok)} .badge.bad b{color:var(--bad)}
.note{border-left:4px solid var(--accent);background:var(--soft);padding:8px 12px;margin:10px 0;font-size:.92rem}
.note.bad{border-left-color:var(--bad);background:#fdf0ef}
.warnings{border:1px solid #e3a9a4;background:#fdf0ef;border-left:5px solid var(--bad);padding:10px 14px;
 margin:14px 0;border-radius:4px}
.warnings h2{border:0;margin:0 0 4px;font-size:1.05rem;color:var(--bad);padding:0}
.warnings ul{margin:4px 0 0 18px;padding:0}
table{border-collapse:collapse;margin:10px 0 16px;font-size:.9rem;font-variant-numeric:tabular-nums}
caption{caption-side:top;text-align:left;font-size:.88rem;color:var(--muted);padding:0 0 6px}
table.est{width:100%}
table.data{min-width:50%}
td code{white-space:nowrap}
th,td{padding:5px 9px;border-bottom:1px solid var(--line);vertical-align:top}
thead th{text-align:left;background:var(--soft);border-bottom:2px solid #c4cad6;font-weight:600;white-space:nowrap}
td.num,th.num{text-align:right;white-space:nowrap}
td.flag{color:var(--bad);font-weight:600}
table.kv th{text-align:left;font-weight:600;color:#39424f;width:34%;background:none}
table.kv td.num{text-align:left}
.unit{color:var(--muted);font-weight:400}
table.mat{margin:0;font-size:.82rem;border-left:1px solid #9aa3b2;border-right:1px solid #9aa3b2}
table.mat td{border:0;padding:1px 8px;text-align:right}
table.rec{margin:0;font-size:.82rem}
table.rec th{white-space:normal;overflow-wrap:anywhere;background:none;font-weight:600;color:var(--muted);padding:1px 8px;border-bottom:1px solid var(--line)}
table.rec td{padding:1px 8px;border:0}
table.rec.nv td,table.rec.nv th{padding:1px 3px;font-size:.76rem;white-space:nowrap}
table.rec td:first-child{max-width:280px;overflow-wrap:break-word}
.scroll{overflow-x:auto;max-width:100%}
table.kv th{overflow-wrap:break-word}
table.kv td{overflow-wrap:break-word}
table.kv{table-layout:fixed;width:100%}
table.kv th{width:30%}
main{overflow-wrap:break-word}
.status{font-size:.82rem;padding:1px 6px;border-radius:3px;background:var(--soft);border:1px solid var(--line)}
.status.fixed{color:var(--muted)} .status.derived{color:#6a4c93}
.status.notdet{color:#fff;background:#8a5a00;border-color:#8a5a00}
tr.notid td{color:var(--bad)}
tr.notdet td{color:#8a5a00;background:#fff8ec}
tr.notdet td.num{text-decoration:line-through;text-decoration-color:#d6b27a}
.verdict{border:1px solid var(--line);border-left:5px solid var(--accent);background:var(--soft);padding:10px 14px;
 margin:14px 0;border-radius:4px}
.verdict h2{border:0;margin:0 0 4px;font-size:1.05rem;padding:0}
.verdict ul{margin:4px 0 0 0;padding:0;list-style:none}
.verdict li{margin:3px 0;padding-left:18px;position:relative}
.verdict li:before{content:"•";position:absolute;left:4px;color:var(--muted)}
.verdict li.ok:before{content:"✓";color:var(--ok)} .verdict li.bad:before{content:"✗";color:var(--bad)}
.verdict li.warn:before{content:"!";color:#8a5a00;font-weight:700}
.vec{display:flex;flex-wrap:wrap;gap:2px 0;border-left:1px solid #9aa3b2;border-right:1px solid #9aa3b2;
 padding:0 4px;width:fit-content;max-width:100%;font-size:.82rem}
.vec .vi{display:inline-block;min-width:6.2em;text-align:right;padding:0 4px;white-space:nowrap}
.chan{white-space:nowrap;display:inline-block;margin-right:6px}
table.data{width:100%} table.data.si{width:auto;min-width:60%}
figure{margin:14px 0 22px;padding:0}
figure img{display:block;max-width:100%;height:auto;border:1px solid var(--line);border-radius:3px}
figcaption{font-size:.86rem;color:var(--muted);margin-top:6px}
code{font-family:"DejaVu Sans Mono",Menlo,Consolas,monospace;font-size:.84rem;background:var(--soft);
 padding:1px 4px;border-radius:3px;word-break:break-all}
footer{margin-top:40px;border-top:1px solid var(--line);padding-top:8px;font-size:.82rem;color:var(--muted)}
details.sec{margin:18px 0 0}
details.sec>summary{cursor:pointer;list-style:none}
details.sec>summary::-webkit-details-marker{display:none}
details.sec>summary h2{display:inline-block;width:100%;margin:14px 0 6px}
details.sec>summary h2:before{content:"▸ ";color:var(--accent)}
details.sec[open]>summary h2:before{content:"▾ "}
details>summary{cursor:pointer;color:var(--accent);font-size:.92rem;margin:8px 0}
.headline{font-size:1.08rem;font-weight:600;margin:4px 0 10px}
.headline.bad{color:var(--bad)} .headline.ok{color:var(--ok)} .headline.warn{color:#8a5a00}
.vcols{display:grid;grid-template-columns:minmax(0,1fr) minmax(0,1.25fr);gap:18px}
@media (max-width:800px){.vcols{grid-template-columns:1fr}}
.verdict code{word-break:normal;white-space:nowrap}
.verdict h3{margin:4px 0 6px;font-size:.98rem}
table.found{margin:0 0 6px;font-size:.86rem;width:100%}
table.found td,table.found th{padding:2px 6px}
.grade{font-size:.8rem;padding:1px 6px;border-radius:3px;background:#fff;border:1px solid var(--line);white-space:nowrap}
.grade.well{color:var(--ok)} .grade.poor,.grade.flagged,.grade.noSE{color:#8a5a00}
.grade.notdet,.grade.notdetermined{color:#fff;background:#8a5a00;border-color:#8a5a00}
.grade.fixed,.grade.known{color:var(--muted)} .grade.derived{color:#6a4c93}
@media print{details{display:block}main{max-width:none;padding:0} h2{break-after:avoid} figure{break-inside:avoid}}
"""


def page(doc_title: str, body: str) -> str:
    """A complete HTML document: ``body`` (trusted HTML) inside ``<main>`` with the shared style."""
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">"
            f"<meta name=\"generator\" content=\"shipid {html.escape(shipid.__version__)}\">"
            f"<title>{html.escape(doc_title)}</title><style>{CSS}</style></head>\n<body><main>\n"
            f"{body}\n</main></body></html>\n")


__all__ = ["CSS", "page"]
