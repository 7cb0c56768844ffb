import sys

from assets_gen.cli import main

sys.exit(main())
