from shipid.cli import run

run()
