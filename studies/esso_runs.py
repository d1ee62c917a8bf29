"""The Esso Osaka 3 m runs of the papers' training/test splits, as the data set's README lists them
(``README_upstream.md``, "Correspondence table with the paper"): ``miyauchi2022`` (Miyauchi et al. 2022,
Train-TRZ) and ``wakita2022`` (Wakita et al. 2022, Train-TZRB+). Paths relative to ``esso_osaka_3m/data``.
Shared by the study scripts beside it."""

_RND = "random/random_{}.csv"
SPLITS = {
    "miyauchi2022": {
        "train": [_RND.format("06-Aug-2020_16_24_25_4"), _RND.format("06-Aug-2020_16_24_25_5"),
                  _RND.format("06-Aug-2020_16_24_25_6"), "turning/turn_cut_14-Sep-2020_16_09_02.csv",
                  "zigzag/zigzag_31-Jul-2020_13_22_52.csv", "zigzag/zigzag_31-Jul-2020_13_50_28.csv"],
        "test": [_RND.format("06-Aug-2020_16_24_25_3"), "turning/turn_14-Sep-2020_14_50_41.csv",
                 "zigzag/zigzag_31-Jul-2020_14_10_05.csv", "berthing/berthing_12-Nov-2020_11_49_21.csv",
                 "berthing/berthing_12-Nov-2020_13_21_03.csv"],
    },
    "wakita2022": {
        "train": [_RND.format(s) for s in ("03-Aug-2020_11_04_37", "06-Aug-2020_16_24_25_1",
                                           "06-Aug-2020_16_24_25_4", "06-Aug-2020_16_24_25_5",
                                           "06-Aug-2020_16_24_25_6", "31-Jul-2020_12_29_58",
                                           "31-Jul-2020_12_48_39", "31-Jul-2020_14_52_18")]
        + [f"turning/turn_{s}.csv" for s in ("14-Oct-2020_14_08_51", "14-Oct-2020_14_17_39",
                                            "14-Oct-2020_14_29_49", "14-Oct-2020_14_39_54",
                                            "14-Oct-2020_14_56_07", "14-Oct-2020_15_21_57",
                                            "14-Sep-2020_13_39_32", "14-Sep-2020_13_51_45",
                                            "14-Sep-2020_14_16_04", "14-Sep-2020_14_50_41",
                                            "14-Sep-2020_15_47_33", "14-Sep-2020_15_58_08",
                                            "cut_14-Sep-2020_15_58_08", "cut_14-Sep-2020_16_09_02")]
        + [f"zigzag/zigzag_31-Jul-2020_{s}.csv" for s in ("13_04_24", "13_14_21", "13_22_52", "13_29_19",
                                                          "13_50_28", "13_57_45", "14_03_39", "14_10_05")]
        + [f"berthing/berthing_12-Nov-2020_{s}.csv" for s in ("11_07_23", "11_14_47", "11_21_46",
                                                             "13_09_11", "13_37_05")],
        "test": [_RND.format("06-Aug-2020_16_24_25_3"), "turning/turn_14-Oct-2020_15_06_53.csv",
                 "zigzag/zigzag_31-Jul-2020_13_42_53.csv", "berthing/berthing_12-Nov-2020_11_38_50.csv",
                 "berthing/berthing_12-Nov-2020_11_49_21.csv", "berthing/berthing_12-Nov-2020_13_21_03.csv"],
    },
}
