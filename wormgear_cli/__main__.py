from wormgear_cli.cli import main

main()
