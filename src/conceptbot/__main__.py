"""Allow ``python -m conceptbot``."""

from conceptbot.cli.main import main

if __name__ == "__main__":
    main()
