"""`python -m lumipose_cli ...` runs `lumipose ...`."""

import sys

from lumipose_cli.main import main

sys.exit(main())
