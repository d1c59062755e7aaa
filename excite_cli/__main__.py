from excite_cli.cli import app

app()
