"""Generated gRPC stubs of tetrefine.v1 (python/tools/generate_stubs.py); do not edit."""
