"""Shared test set-up: this folder is on ``sys.path``, so every test imports the one
independent DH oracle (``dh_oracle``) the same way."""
