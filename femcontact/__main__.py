"""`python -m femcontact ...` works like `femcontact ...`."""
import sys

from femcontact.cli import main

sys.exit(main())
