"""`python -m femcontact ...` works like `femcontact ...`."""
from femcontact.cli import console

console()
