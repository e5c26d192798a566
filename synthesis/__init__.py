"""synthesis: the tolerance synthesis loop and the command line."""
