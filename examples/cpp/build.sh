#!/bin/sh
# sh build.sh: compile patrol.cpp with the generated C++ client (PLATFORMCTRL: its folder, default the toolkit's
# clients/generated/cpp; or `pltf stubs --lang cpp --out DIR`) into build/patrol. C++17, g++ (CXX), no other
# dependency. Run: ./build/patrol --target HOST:PORT --stations A,B,C
set -e
cd "$(dirname "$0")"
GEN="${PLATFORMCTRL:-../../clients/generated/cpp}"
CXX="${CXX:-g++}"
set -- -std=c++17 -O1 -Wall -Wextra -I"$GEN/include"  # the compiler flags
mkdir -p build
"$CXX" "$@" -c "$GEN/src/protocol.cpp" -o build/protocol.o &
"$CXX" "$@" -c "$GEN/src/runtime.cpp" -o build/runtime.o
wait $!
"$CXX" "$@" patrol.cpp build/runtime.o build/protocol.o -o build/patrol
