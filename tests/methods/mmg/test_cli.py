"""The text output of ``shipid identify mmg`` (``shipid.methods.mmg.cli._print_result``)."""

from shipid.methods.mmg.cli import _print_result
from shipid.result import Estimate


def _result(est, diag):
    return type("R", (), {"estimates": est, "diagnostics": diag,
                          "model": {"structure": "yasukawa2015", "structure_candidate": "full"}})()


def test_identify_table_never_prints_a_coefficient_undetermined_with_the_form_term_as_estimated(capsys):
    """The text table of ``identify mmg``: a coefficient whose SE alone is below |value| but whose std with
    the model-form term is not (pipeline.form_check's not_determined_with_form) reads 'not determined with
    form', the others keep their status."""
    est = {"X_vv": Estimate(-0.19, 0.098, "-", "estimated", ""), "N_r": Estimate(-0.034, 0.0026, "-", "estimated", ""),
           "X_vr": Estimate(-0.06, 0.075, "-", "not determined", "")}
    diag = {"form_check": {"std_with_form": {"X_vv": 0.29, "N_r": 0.0066}, "not_determined_with_form": ["X_vv"]}}
    _print_result(_result(est, diag))
    rows = {ln.split()[0]: ln for ln in capsys.readouterr().out.splitlines() if ln.split()}
    assert rows["X_vv"].endswith("not determined with form")
    assert rows["N_r"].endswith("  estimated") and rows["X_vr"].endswith("  not determined")


def test_a_candidate_that_could_not_be_scored_is_explained_once(capsys):
    """A CV table row with score inf (fit failed or simulation diverged in a fold) gets one explaining line."""
    row = {"score": 1.86, "psi_rms": 10.6, "pos_rms": 0.79}
    sel = {"method": "4-fold CV", "table": {"full": row, "cubic": {"score": float("inf"), "psi_rms": float("inf"),
                                                                    "pos_rms": float("inf")}}}
    est = {"N_r": Estimate(-0.034, 0.0026, "-", "estimated", "")}
    _print_result(_result(est, {"structure_selection": sel}))
    out = capsys.readouterr().out
    assert out.count("score inf: the candidate's fit failed or its simulation diverged") == 1
    _print_result(_result(est, {"structure_selection": dict(sel, table={"full": row})}))
    assert "score inf" not in capsys.readouterr().out


def test_the_staged_selection_prints_its_second_table_the_choice_and_why(capsys):
    """With the staged selection (shipid.methods.mmg.staged) the text output has the regression table, the
    refinement table with the chosen row and criterion marked, and the 'why' line of MODEL.json."""
    row = {"score": 1.86, "psi_rms": 10.6, "pos_rms": 0.79}
    ref = {"full/regression": dict(row), "full/output-error": dict(row, score=1.40),
           "full+rudder-offset/output-error": dict(row, score=1.25)}
    sel = {"method": "staged CV", "table": {"full": row}, "refinement_table": ref, "chosen": "full+rudder-offset",
           "chosen_criterion": "output-error", "why": "lowest CV score of the 3 rows scored: 1.2500"}
    res = _result({"N_r": Estimate(-0.034, 0.0026, "-", "estimated", "")}, {"structure_selection": sel})
    res.model = {"structure": "yasukawa2015", "structure_candidate": "full+rudder-offset"}
    _print_result(res)
    lines = capsys.readouterr().out.splitlines()
    marked = [ln for ln in lines if ln.endswith("<-")]
    assert len(marked) == 1 and marked[0].split()[0] == "full+rudder-offset/output-error"
    assert "  why: lowest CV score of the 3 rows scored: 1.2500" in lines
