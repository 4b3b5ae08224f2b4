"""Diagnosis: where a simulator departs from a recording, and which physical effect it misses."""
