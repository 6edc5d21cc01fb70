package xsd

import (
	"bytes"
	"encoding/xml"
	"fmt"
	"io"
	"math/big"
	"regexp"
	"strings"
	"unicode"
)

// elem is a document element as the validator sees it.
type elem struct {
	name     string
	attrs    []xml.Attr
	children []*elem
	text     bool // non-blank character data directly inside
	line     int
}

func (e *elem) get(name string) (string, bool) {
	for _, a := range e.attrs {
		if a.Name.Space == "" && a.Name.Local == name {
			return a.Value, true
		}
	}
	return "", false
}

// Decoder makes the xml.Decoder a document is read with (its charset reader, strictness).
type Decoder func(io.Reader) *xml.Decoder

// Validate checks a well-formed document against the schema: its root must be a global element.
func (s *Schema) Validate(doc []byte, newDecoder Decoder) error {
	root, err := tree(doc, newDecoder)
	if err != nil {
		return err
	}
	decl, ok := s.elements[root.name]
	if !ok {
		return fmt.Errorf("<%s> is not a document element of this schema", root.name)
	}
	v := &validation{ids: map[string]bool{}}
	if err := v.element(root, decl); err != nil {
		return err
	}
	for _, ref := range v.idrefs {
		if !v.ids[ref] {
			return fmt.Errorf("IDREF %q names no ID of the document", ref)
		}
	}
	return nil
}

func tree(doc []byte, newDecoder Decoder) (*elem, error) {
	d := newDecoder(bytes.NewReader(doc))
	var stack []*elem
	var root *elem
	for {
		tok, err := d.Token()
		if err == io.EOF {
			break
		}
		if err != nil {
			return nil, err
		}
		switch t := tok.(type) {
		case xml.StartElement:
			line, _ := d.InputPos()
			e := &elem{name: t.Name.Local, attrs: t.Attr, line: line}
			if t.Name.Space != "" {
				return nil, fmt.Errorf("line %d: <%s> in namespace %q (the schemas have none)", line, e.name, t.Name.Space)
			}
			if len(stack) > 0 {
				parent := stack[len(stack)-1]
				parent.children = append(parent.children, e)
			} else {
				root = e
			}
			stack = append(stack, e)
		case xml.EndElement:
			stack = stack[:len(stack)-1]
		case xml.CharData:
			if len(stack) > 0 && len(bytes.TrimSpace(t)) > 0 {
				stack[len(stack)-1].text = true
			}
		}
	}
	if root == nil {
		return nil, fmt.Errorf("no root element")
	}
	return root, nil
}

type validation struct {
	ids    map[string]bool
	idrefs []string
}

func (v *validation) element(e *elem, decl *element) error {
	ct := decl.typ
	if ct == nil {
		return nil // xs:anyType
	}
	if e.text && !ct.mixed {
		return fmt.Errorf("line %d: <%s> holds text", e.line, e.name)
	}
	seen := map[string]bool{}
	for _, a := range e.attrs {
		if a.Name.Space == "xmlns" || (a.Name.Space == "" && a.Name.Local == "xmlns") || a.Name.Space == "xml" ||
			a.Name.Space == "http://www.w3.org/XML/1998/namespace" {
			continue
		}
		ad, ok := ct.attrs[a.Name.Local]
		if !ok || a.Name.Space != "" {
			return fmt.Errorf("line %d: <%s> has no attribute %q", e.line, e.name, a.Name.Local)
		}
		seen[a.Name.Local] = true
		if err := v.value(ad.typ, a.Value); err != nil {
			return fmt.Errorf("line %d: <%s %s=%q>: %v", e.line, e.name, a.Name.Local, a.Value, err)
		}
	}
	for name, ad := range ct.attrs {
		if ad.required && !seen[name] {
			return fmt.Errorf("line %d: <%s> lacks the attribute %q", e.line, e.name, name)
		}
	}
	if ct.content == nil {
		if len(e.children) > 0 {
			return fmt.Errorf("line %d: <%s> must be empty, holds <%s>", e.line, e.name, e.children[0].name)
		}
	} else {
		i, err := v.match(ct.content, e.children, 0)
		if err != nil {
			return fmt.Errorf("in <%s>: %v", e.name, err)
		}
		if i < len(e.children) {
			c := e.children[i]
			return fmt.Errorf("line %d: <%s> is not expected in <%s>", c.line, c.name, e.name)
		}
	}
	for _, id := range decl.constraints {
		if err := v.identity(e, id, decl); err != nil {
			return err
		}
	}
	return nil
}

// match consumes the children p takes from index i on: as many rounds as p allows, greedily.
func (v *validation) match(p *particle, kids []*elem, i int) (int, error) {
	for n := 0; p.max < 0 || n < p.max; n++ {
		if n >= p.min && (i >= len(kids) || !starts(p, kids[i].name)) {
			break
		}
		j, err := v.once(p, kids, i)
		if err != nil {
			return i, err
		}
		if j == i && n >= p.min {
			break
		}
		i = j
	}
	return i, nil
}

func (v *validation) once(p *particle, kids []*elem, i int) (int, error) {
	switch {
	case p.elem != nil:
		if i >= len(kids) || kids[i].name != p.elem.name {
			return i, fmt.Errorf("<%s> expected%s", p.elem.name, at(kids, i))
		}
		return i + 1, v.element(kids[i], p.elem)
	case p.seq:
		for _, item := range p.items {
			j, err := v.match(item, kids, i)
			if err != nil {
				return i, err
			}
			i = j
		}
		return i, nil
	}
	for _, item := range p.items { // a choice: the branch the next child starts
		if i < len(kids) && starts(item, kids[i].name) {
			return v.match(item, kids, i)
		}
	}
	for _, item := range p.items {
		if nullable(item) {
			return i, nil
		}
	}
	return i, fmt.Errorf("one of %s expected%s", strings.Join(firsts(p, nil), ", "), at(kids, i))
}

func at(kids []*elem, i int) string {
	if i < len(kids) {
		return fmt.Sprintf(", not <%s> (line %d)", kids[i].name, kids[i].line)
	}
	return " before the end"
}

func starts(p *particle, name string) bool {
	for _, f := range firsts(p, nil) {
		if f == "<"+name+">" {
			return true
		}
	}
	return false
}

func firsts(p *particle, out []string) []string {
	if p.elem != nil {
		return append(out, "<"+p.elem.name+">")
	}
	for _, item := range p.items {
		out = firsts(item, out)
		if p.seq && !nullable(item) {
			break
		}
	}
	return out
}

func nullable(p *particle) bool {
	if p.min == 0 || p.elem != nil {
		return p.min == 0
	}
	for _, item := range p.items {
		if n := nullable(item); p.seq && !n {
			return false
		} else if !p.seq && n {
			return true
		}
	}
	return p.seq
}

var (
	decimalText = regexp.MustCompile(`^[+-]?([0-9]+(\.[0-9]*)?|\.[0-9]+)$`)
	integerText = regexp.MustCompile(`^[+-]?[0-9]+$`)
)

var tiny, _ = new(big.Rat).SetString("1e-31")

// collapse is the whiteSpace="collapse" of every built-in type but xs:string.
func collapse(s string) string { return strings.Join(strings.Fields(s), " ") }

func nameChar(r rune, colon bool) bool {
	return unicode.IsLetter(r) || unicode.IsDigit(r) || r == '.' || r == '-' || r == '_' || (colon && r == ':') ||
		unicode.Is(unicode.Mn, r) || unicode.Is(unicode.Mc, r) || r == 0xB7
}

func (v *validation) value(t *simpleType, raw string) error {
	val := raw
	if t.base != "string" {
		val = collapse(raw)
	}
	switch t.base {
	case "NMTOKEN":
		if val == "" || strings.IndexFunc(val, func(r rune) bool { return !nameChar(r, true) }) >= 0 {
			return fmt.Errorf("not an NMTOKEN")
		}
	case "ID", "IDREF":
		first := []rune(val + " ")[0]
		if val == "" || !(unicode.IsLetter(first) || first == '_') ||
			strings.IndexFunc(val, func(r rune) bool { return !nameChar(r, false) }) >= 0 {
			return fmt.Errorf("not an NCName")
		}
		if t.base == "ID" {
			if v.ids[val] {
				return fmt.Errorf("the ID %q twice", val)
			}
			v.ids[val] = true
		} else {
			v.idrefs = append(v.idrefs, val)
		}
	case "boolean":
		if val != "true" && val != "false" && val != "1" && val != "0" {
			return fmt.Errorf("not a boolean")
		}
	case "decimal", "integer":
		re := decimalText
		if t.base == "integer" {
			re = integerText
		}
		if !re.MatchString(val) {
			return fmt.Errorf("not an %s", map[string]string{"decimal": "xs:decimal", "integer": "xs:integer"}[t.base])
		}
		if out := outOfRange(val, t.min, t.max); out != "" {
			return fmt.Errorf("%s", out)
		}
	}
	for _, p := range t.patterns {
		if !p.MatchString(val) {
			return fmt.Errorf("does not match the pattern %s", p)
		}
	}
	return nil
}

// outOfRange compares a decimal text with inclusive bounds without building huge numbers: a peer may send a
// million digits. Integer parts over 30 digits are beyond every bound the schemas have; fractions are compared
// on their first 30 digits, a non-zero rest counting as a step away from zero.
func outOfRange(val string, lo, hi *big.Rat) string {
	if lo == nil && hi == nil {
		return ""
	}
	neg := strings.HasPrefix(val, "-")
	digits := strings.TrimLeft(val, "+-")
	intPart, frac, _ := strings.Cut(digits, ".")
	intPart = strings.TrimLeft(intPart, "0")
	frac = strings.TrimRight(frac, "0")
	var r *big.Rat
	if len(intPart) > 30 {
		if neg && lo != nil || !neg && hi != nil {
			return "out of range"
		}
		return ""
	}
	rest := ""
	if len(frac) > 30 {
		frac, rest = frac[:30], frac[30:]
	}
	r, _ = new(big.Rat).SetString("0" + intPart + "." + frac + "0")
	if rest != "" {
		r.Add(r, tiny) // beyond the 30 digits kept: a little further from zero
	}
	if neg {
		r.Neg(r)
	}
	if (lo != nil && r.Cmp(lo) < 0) || (hi != nil && r.Cmp(hi) > 0) {
		return "out of range"
	}
	return ""
}
