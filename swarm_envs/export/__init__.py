"""Export of trained policies and their observation builder as dependency-free C for robot firmware."""
