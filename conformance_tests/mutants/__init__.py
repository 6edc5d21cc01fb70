"""Mutation testing of the suite itself: deliberately broken variants of the reference server.

Two carriers, neither of which edits reference_server/:
- wire mutants (``proxy.FrameProxy`` + a ``WireMutant``): a TCP proxy in front of the real server rewrites,
  drops, delays or answers frames;
- model mutants (``serve.py``): the reference server started through a bootstrap that first monkeypatches one
  rule of its platform model (the state chart table, the parameter store, the document store, the drive).

``catalogue.MUTANTS`` lists them, each with the case that must kill it (the case that names the broken
requirement); tests/conformance_tests/test_mutants.py checks that it does and that the unbroken server passes.
"""
