"""What a user runs: the command line, animate, info, export and preview."""
