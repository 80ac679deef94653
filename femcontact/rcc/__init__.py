"""The remote-centre-compliance device as a 3-D pin-jointed truss, and its command line."""
