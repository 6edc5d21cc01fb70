package main

import (
	"os"
	"path/filepath"
)

// dirDisk is the data directory (--data-dir) behind CMD_LOAD_* and CMD_SAVE_* (E-CMD-008); SAVE writes a file
// atomically (a temporary file, then rename).
type dirDisk string

func (d dirDisk) Read(name string) ([]byte, error) {
	return os.ReadFile(filepath.Join(string(d), name))
}

func (d dirDisk) Write(name string, data []byte) error {
	path := filepath.Join(string(d), name)
	if err := os.MkdirAll(filepath.Dir(path), 0o755); err != nil {
		return err
	}
	tmp := path + ".tmp"
	if err := os.WriteFile(tmp, data, 0o644); err != nil {
		return err
	}
	return os.Rename(tmp, path)
}
