// genparams writes internal/params/table_gen.go from spec/parameters.yaml and spec/enums.yaml.
// Run from emulator/: go run ./cmd/genparams
package main

import (
	"fmt"
	"os"

	"pltf/emulator/internal/params/specgen"
)

func main() {
	p, err1 := os.ReadFile("../spec/parameters.yaml")
	e, err2 := os.ReadFile("../spec/enums.yaml")
	if err1 != nil || err2 != nil {
		fmt.Fprintln(os.Stderr, "genparams: run from emulator/ (reads ../spec/parameters.yaml and ../spec/enums.yaml)")
		os.Exit(2)
	}
	entries, err := specgen.Parse(p, e)
	if err == nil {
		var src []byte
		if src, err = specgen.Render(entries); err == nil {
			err = os.WriteFile("internal/params/table_gen.go", src, 0o644)
		}
	}
	if err != nil {
		fmt.Fprintln(os.Stderr, "genparams:", err)
		os.Exit(1)
	}
	fmt.Printf("internal/params/table_gen.go: %d parameters\n", len(entries))
}
