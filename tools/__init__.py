"""facetrack's Python tools, one package run from the repository root with Debian's python3:

    /usr/bin/python3 -m tools.train.refine.train_refine --help

tools/README.md maps them: train/ makes the shipped models, experiments/ the measurements the docs cite.
"""
