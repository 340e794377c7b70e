import sys

from brdfz.view import main

sys.exit(main())
