from flctool.cli import run

run()
