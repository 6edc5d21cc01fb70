// The PlatformCtrl emulator: a second, independent implementation of the protocol (issue 17), written from
// spec/ and the guide. Standard library plus the generated Go client codec of clients/generated/go.
module pltf/emulator

go 1.22

require platformctrl v0.0.0

replace platformctrl => ../clients/generated/go
