"""The Esso Osaka training/test splits of both papers (shipid.io.basins.SPLITS)."""

from shipid.io.basins import SPLITS


def test_splits_are_disjoint_and_match_the_readme_counts():
    # README_upstream.md: Miyauchi Train-TRZ has 6 runs and 5 test runs; Wakita Train-TZRB+ 35, test 6
    for name, n_train, n_test in (("miyauchi2022", 6, 5), ("wakita2022", 35, 6)):
        sp = SPLITS[name]
        assert len(sp["train"]) == n_train and len(sp["test"]) == n_test
        assert not set(sp["train"]) & set(sp["test"])


def test_split_files_exist(data_root):
    root = data_root
    for sp in SPLITS.values():
        for f in sp["train"] + sp["test"]:
            assert (root / "esso_osaka_3m" / "data" / f).is_file(), f
