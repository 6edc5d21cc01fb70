// Package params is the emulator's parameter store: the table of spec/parameters.yaml (table_gen.go), the
// value texts of CMD_SET_PLTF_PARAM / CMD_GET_PLTF_PARAM (guide 6.3, 6.4) and their checks.
//
// Rules (errata E-PAR-003..007, E-PAR-024, E-PAR-027):
//   - keys are compared exactly, byte for byte (E-PAR-003);
//   - a SET is refused as a whole - unknown key, read-only parameter, malformed text, value out of the real
//     range - and the old value stays (E-PAR-007); there is never a reply to a SET;
//   - values are kept as numbers and written back in one canonical text (E-PAR-006, E-PAR-027).
package params

import (
	"errors"
	"math"
	"regexp"
	"strconv"
	"strings"
)

// The data types of guide 6.4 (enum ParamDataType).
const (
	Boolean = 0
	Integer = 1
	Double  = 2
)

// Param is one row of the table.
type Param struct {
	Name     string
	Category int
	Type     int
	Default  float64
	Min, Max float64 // the real, inclusive range
	Unit     string
	Writable bool
}

// WireBounds are the INT minimum and maximum of the reply (E-PAR-004): a DOUBLE parameter sends floor(min)
// and ceil(max), the smallest integer interval holding its range; INTEGER and BOOLEAN send theirs unchanged.
func (p *Param) WireBounds() (int32, int32) {
	if p.Type == Double {
		return int32(math.Floor(p.Min)), int32(math.Ceil(p.Max))
	}
	return int32(p.Min), int32(p.Max)
}

// Store holds the current value of every parameter it offers.
type Store struct {
	order  []*Param
	byName map[string]*Param
	values map[string]float64
}

// NewStore offers every parameter of Table except those named in omit (E-PAR-024: a value the emulator does
// not have, such as VelWatchdogTime without a watchdog, is not reported at all), each at its default.
func NewStore(omit ...string) *Store {
	skip := map[string]bool{}
	for _, n := range omit {
		skip[n] = true
	}
	s := &Store{byName: map[string]*Param{}, values: map[string]float64{}}
	for i := range Table {
		p := &Table[i]
		if skip[p.Name] {
			continue
		}
		s.order = append(s.order, p)
		s.byName[p.Name] = p
		s.values[p.Name] = p.Default
	}
	return s
}

// All is the offered parameters in table order (E-PAR-026).
func (s *Store) All() []*Param { return s.order }

// Lookup finds a parameter by its exact key.
func (s *Store) Lookup(key string) (*Param, bool) {
	p, ok := s.byName[key]
	return p, ok
}

// Value is the current number of a parameter (BOOLEAN 0/1); fallback when the key is not offered.
func (s *Store) Value(key string, fallback float64) float64 {
	if v, ok := s.values[key]; ok {
		return v
	}
	return fallback
}

// Text is the value text of a parameter as the replies carry it.
func (s *Store) Text(p *Param) string { return Format(p.Type, s.values[p.Name]) }

// Set changes a parameter from a value text, or refuses with the reason and changes nothing (E-PAR-007).
func (s *Store) Set(key, text string) error {
	p, ok := s.byName[key]
	if !ok {
		return errors.New("unknown parameter")
	}
	if !p.Writable {
		return errors.New("read-only parameter (parameter file, E-PAR-024)")
	}
	v, err := Parse(p.Type, text)
	if err != nil {
		return err
	}
	if v < p.Min || v > p.Max {
		return errors.New("value out of range")
	}
	s.values[key] = v
	return nil
}

// SetDefault changes a value at start-up, read-only ones included (the emulator's stand-in for its parameter files).
func (s *Store) SetDefault(key string, v float64) {
	if _, ok := s.byName[key]; ok {
		s.values[key] = v
	}
}

var (
	// E-PAR-006: INTEGER is [+-]?digits; DOUBLE a decimal with "." and an optional exponent.
	integerText = regexp.MustCompile(`^[+-]?[0-9]+$`)
	doubleText  = regexp.MustCompile(`^[+-]?([0-9]+(\.[0-9]+)?|\.[0-9]+)([eE][+-]?[0-9]+)?$`)
)

// Parse reads a value text of the given type (E-PAR-005, E-PAR-006): surrounding blanks are stripped; BOOLEAN
// is true, false, 1 or 0 in any letter case; nan, inf and numbers that overflow are refused.
func Parse(dataType int, text string) (float64, error) {
	t := strings.Trim(text, " \t\r\n")
	switch dataType {
	case Boolean:
		switch strings.ToLower(t) {
		case "true", "1":
			return 1, nil
		case "false", "0":
			return 0, nil
		}
		return 0, errors.New("not a BOOLEAN value text (true, false, 1, 0)")
	case Integer:
		if !integerText.MatchString(t) {
			return 0, errors.New("not an INTEGER value text")
		}
		n, err := strconv.ParseInt(t, 10, 64)
		if err != nil || n < math.MinInt32 || n > math.MaxInt32 {
			return 0, errors.New("INTEGER value overflows")
		}
		return float64(n), nil
	default:
		if !doubleText.MatchString(t) {
			return 0, errors.New("not a DOUBLE value text")
		}
		d, err := strconv.ParseFloat(t, 64)
		if err != nil || math.IsInf(d, 0) {
			return 0, errors.New("DOUBLE value overflows")
		}
		return d, nil
	}
}

// Format writes a value (E-PAR-006, E-PAR-027): BOOLEAN lower-case true/false, INTEGER decimal digits, DOUBLE
// the shortest text that reads back to the same number, in the form of Python's repr (0.6, 1000.0, 1e-05).
func Format(dataType int, v float64) string {
	switch dataType {
	case Boolean:
		if v != 0 {
			return "true"
		}
		return "false"
	case Integer:
		return strconv.FormatInt(int64(v), 10)
	}
	if a := math.Abs(v); a != 0 && (a < 1e-4 || a >= 1e16) {
		return strconv.FormatFloat(v, 'e', -1, 64)
	}
	s := strconv.FormatFloat(v, 'f', -1, 64)
	if !strings.Contains(s, ".") {
		s += ".0"
	}
	return s
}
