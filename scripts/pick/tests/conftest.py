"""The pick trainer's tests: scripts/pick on the import path, and the repository's root."""
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
PICK = os.path.dirname(HERE)
ROOT = os.path.dirname(os.path.dirname(PICK))
sys.path.insert(0, PICK)
