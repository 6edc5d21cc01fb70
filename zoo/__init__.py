"""A zoo of foreign PlatformCtrl targets for the suite, the fuzzer and the benchmarks (issue 17), and the one
launcher that starts any target on ephemeral ports (launch.py). See zoo/README.md."""
