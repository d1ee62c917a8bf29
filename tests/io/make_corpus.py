"""Regenerate the small trial files under ``tests/io/bad/`` and ``tests/io/good/``.

The files are committed; this script documents how each was made and rebuilds them
(``python tests/io/make_corpus.py``). Every file is synthetic: nothing here comes
from the real data sets in ``../shared/data``, which must not be copied. What each
bad file is expected to be answered with lives in ``test_bad_corpus.py``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

HERE = Path(__file__).parent
BAD = HERE / "bad"
GOOD = HERE / "good"

HEADER = "t [s],x [m],u [m/s],psi [rad]"


def rows(n=6, dt=0.1, t0=0.0):
    """Plausible rows of a ship moving ahead at 1 m/s while turning slowly."""
    out = []
    for k in range(n):
        t = t0 + k * dt
        out.append([f"{t:.10g}", f"{1.0 * t:.6f}", "1.000000", f"{0.01 * t:.6f}"])
    return out


def text(header, body, nl="\n"):
    return nl.join([header] + [",".join(r) for r in body]) + nl


def write(path: Path, content):
    path.parent.mkdir(parents=True, exist_ok=True)
    if isinstance(content, str):
        path.write_bytes(content.encode("utf-8"))
    else:
        path.write_bytes(content)


def parquet_bytes(columns: dict, metadata: dict | None = None) -> bytes:
    import io
    import pyarrow as pa
    import pyarrow.parquet as pq
    table = pa.table({k: pa.array(v, type=pa.float64()) for k, v in columns.items()})
    if metadata:
        table = table.replace_schema_metadata(metadata)
    buf = io.BytesIO()
    pq.write_table(table, buf)
    return buf.getvalue()


def kvlcc2_rows(n=5, dt=0.05):
    out = []
    for k in range(n):
        t = k * dt
        vals = [t, 2.0 + 1.18 * t, 0.0, 0.0, 1.18, 0.0, 0.0, 0.0, 0.0, 10.23, 41.2, 1.03]
        out.append("".join(f"{v:19.9f}" for v in vals))
    return out


KVLCC2_HEAD = [" Synthetic test file in the HSVA layout", " KVLCC2", " Z10\u00b0/10\u00b0 made up",
               " Time series of motions"]


def bad_files():
    b = {}
    r = rows()
    b["empty.csv"] = ""
    b["whitespace_only.csv"] = "  \n\n \n"
    b["header_only.csv"] = HEADER + "\n"
    body = [list(x) for x in r]; body[2][2] = "nan"
    b["nan_value.csv"] = text(HEADER, body)
    body = [list(x) for x in r]; body[1][3] = ""
    b["empty_cell.csv"] = text(HEADER, body)
    body = [list(x) for x in r]; body[3][1] = "inf"
    b["inf_value.csv"] = text(HEADER, body)
    body = [list(x) for x in r]; body[3][0], body[4][0] = body[4][0], body[3][0]
    b["nonmonotonic_time.csv"] = text(HEADER, body)
    body = [list(x) for x in r]; body[3][0] = body[2][0]
    b["duplicate_timestamp.csv"] = text(HEADER, body)
    body = [list(x) for x in r][::-1]
    b["negative_dt.csv"] = text(HEADER, body)
    b["unknown_unit.csv"] = text("t [s],x [m],u [blorps],psi [rad]", r)
    b["missing_channel.csv"] = text(HEADER, r)            # checked with --require u,v,r
    body = [list(x) for x in r]; body[3][2] = "abc"
    b["text_in_numeric.csv"] = text(HEADER, body)
    # ';' and tab files are read since shipid.io.csv_dialect; what stays bad is an unclear dialect
    b["semicolon_mixed_decimal.csv"] = "\n".join([HEADER.replace(",", ";")] + [";".join(x) for x in r[:2]] +
                                                 [";".join(x).replace(".", ",") for x in r[2:]]) + "\n"
    b["ambiguous_delimiter.csv"] = "\n".join(["t [s],x [m];u [m/s],psi [rad]"] +
                                             [f"{x[0]},{x[1]};{x[2]},{x[3]}" for x in r]) + "\n"
    b["pipe_delimiter.csv"] = "\n".join([HEADER.replace(",", "|")] + ["|".join(x) for x in r]) + "\n"
    rng = np.random.default_rng(20261121)
    b["binary_junk.csv"] = rng.integers(0, 256, size=512, dtype=np.uint8).tobytes()
    body = [list(x) for x in r]; body[3][0] = "0.33"
    b["non_uniform_sampling.csv"] = text(HEADER, body)
    b["duplicate_column.csv"] = text("t [s],x [m],u [m/s],x [m]", r)
    b["missing_unit_brackets.csv"] = text("t [s],x,u [m/s],psi [rad]", r)
    body = [list(x) for x in r]; body[2] = body[2][:2]
    b["too_few_fields.csv"] = text(HEADER, body)
    body = [list(x) for x in r]; body[4] = body[4] + ["7.0"]
    b["too_many_fields.csv"] = text(HEADER, body)
    b["header_garbage.csv"] = text("t [s],x [m]]],u [m/s],psi [rad]", r)
    b["no_header_numbers.csv"] = text(",".join(r[0]), r[1:])
    b["empty_header_cell.csv"] = text("t [s],,u [m/s],psi [rad]", r)
    b["no_time_column.csv"] = text("time [s],x [m],u [m/s],psi [rad]", r)
    b["time_in_metres.csv"] = text("t [m],x [m],u [m/s],psi [rad]", r)
    b["wrong_unit_dimension.csv"] = text("t [s],x [m],u [m/s],psi [m]", r)
    b["single_row.csv"] = text(HEADER, r[:1])
    b["time_gap.csv"] = text(HEADER, rows(4) + rows(4, t0=1.0))
    b["time_gap_too_long.csv"] = text(HEADER, rows(4) + rows(4, t0=1.0))   # with --interpolate-gaps 0.5
    body = [list(x) for x in rows(10)]
    for k in (3, 4, 5, 6):
        body[k][2] = ""
    b["nan_gap_too_long.csv"] = text(HEADER, body)                          # with --interpolate-gaps 0.3
    body = [list(x) for x in r]; body[0][2] = ""
    b["nan_at_start.csv"] = text(HEADER, body)                              # with --interpolate-gaps 1
    b["trailing_empty_rows.csv"] = text(HEADER, r + [["", "", "", ""]] * 3)
    b["utf16.csv"] = text(HEADER, r).encode("utf-16")
    cols = {"t": np.arange(6) * 0.1, "x": np.arange(6) * 0.1}
    good_pq = parquet_bytes(cols, {b"shipid.units": b'{"t": "s", "x": "m"}'})
    b["truncated.parquet"] = good_pq[: len(good_pq) // 2]
    b["csv_named_parquet.parquet"] = text(HEADER, r)
    b["parquet_named_csv.csv"] = good_pq
    b["parquet_no_units.parquet"] = parquet_bytes(cols)
    b["wrong_extension.xlsx"] = text(HEADER, r)
    k = kvlcc2_rows()
    k[2] = k[2][:-19]
    b["kvlcc2_short_row.dat"] = ("\n".join(KVLCC2_HEAD + k) + "\n").encode("cp1252")
    b["kvlcc2_header_only.dat"] = ("\n".join(KVLCC2_HEAD) + "\n").encode("cp1252")
    return b


def good_files():
    g = {}
    t = np.arange(8) * 0.1
    header = "t [s],x [m],y [m],psi [deg],u [knot],v [m/s],r [deg/s],delta [deg],n [rpm]"
    body = [[f"{ti:.1f}", f"{0.5 * ti:.4f}", "0.0", f"{2.0 * ti:.3f}", "1.0", "0.01", "2.0", "-5.0", "600"]
            for ti in t]
    g["simple.csv"] = text(header, body)
    g["crlf_bom.csv"] = b"\xef\xbb\xbf" + text(header, body, nl="\r\n").encode("utf-8")
    esso_head = ("t [s],x_position_mid [m],u_velo [m/s],y_position_mid [m],vm_velo [m/s],psi_hat [rad],"
                 "r_angvelo [rad/s],n_prop [rps],delta_rudder [rad],wind_velo_relative_mid [m/s],"
                 "wind_dir_relative_mid [rad],wind_velo_true [m/s],wind_dir_true [rad]")
    esso_body = [[f"{ti:.1f}", f"{0.2 * ti:.4f}", "0.2", "0.0", "0.0", "0.05", "0.0", "12.0", "0.0",
                  "1.0", "6.2", "1.0", "0.1"] for ti in t]
    g["esso_like.csv"] = text(esso_head, esso_body)
    g["custom_names.csv"] = text("time [s],heading,surge [m/s]",
                                 [[f"{ti:.1f}", f"{10.0 * ti:.1f}", "1.5"] for ti in t])
    # repairable: a missing value and a missing sample (0.2 s gaps at 10 Hz)
    body = [list(x) for x in rows(10)]
    body[4][2] = ""
    g["short_gap.csv"] = text(HEADER, body[:6] + body[7:])
    body = [list(x) for x in rows(10)]
    body[5][0] = "0.52"
    g["jittered.csv"] = text(HEADER, body)
    g["small_hsva.dat"] = ("\n".join(KVLCC2_HEAD + kvlcc2_rows(8)) + "\n").encode("cp1252")
    return g


def main():
    for name, content in bad_files().items():
        write(BAD / name, content)
    for name, content in good_files().items():
        write(GOOD / name, content)


if __name__ == "__main__":
    main()
