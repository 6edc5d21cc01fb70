// Package xsd validates the platform's documents against the XSDs of spec/schemas (guide 6.5; E-XML-001 ff.).
//
// Rules: it interprets the subset of XSD 1.0 those four files use - global and local element declarations
// (type, ref, minOccurs, maxOccurs), named and anonymous complex types (sequence and choice groups with
// occurrences, attributes with use="required", mixed), simple types restricting xs:decimal, xs:integer or
// xs:token by minInclusive, maxInclusive and pattern, the built-in types string, token, NMTOKEN, boolean,
// decimal, integer, ID and IDREF, xs:include, and xs:key/xs:keyref with child-path selectors and one
// attribute field. Anything else in a schema is an error when the schema is compiled, never silently
// ignored. Content models are matched greedily, which is exact for the deterministic models XSD 1.0
// requires (Unique Particle Attribution).
package xsd

import (
	"bytes"
	"encoding/xml"
	"fmt"
	"math/big"
	"regexp"
	"strconv"
	"strings"
)

// node is a parsed schema element.
type node struct {
	name     string
	attrs    map[string]string
	children []*node
}

func (n *node) attr(k string) string { return n.attrs[k] }

func parseNode(src []byte) (*node, error) {
	d := xml.NewDecoder(bytes.NewReader(src))
	var stack []*node
	var root *node
	for {
		tok, err := d.Token()
		if err != nil {
			if root != nil && len(stack) == 0 {
				return root, nil
			}
			return nil, err
		}
		switch t := tok.(type) {
		case xml.StartElement:
			n := &node{name: t.Name.Local, attrs: map[string]string{}}
			for _, a := range t.Attr {
				n.attrs[a.Name.Local] = a.Value
			}
			if len(stack) > 0 {
				top := stack[len(stack)-1]
				top.children = append(top.children, n)
			} else {
				root = n
			}
			stack = append(stack, n)
		case xml.EndElement:
			stack = stack[:len(stack)-1]
		}
	}
}

// Schema is a compiled set of schema documents (one file and what it includes).
type Schema struct {
	elements map[string]*element
	complex  map[string]*complexType
	simple   map[string]*simpleType
	pending  []func() error // references resolved after every file is read
}

type element struct {
	name        string
	typ         *complexType // nil: xs:anyType (anything goes)
	constraints []*identity
}

type particle struct {
	elem     *element // an element particle
	seq      bool     // a group: sequence (true) or choice (false)
	items    []*particle
	min, max int // max -1: unbounded
}

type complexType struct {
	content *particle // nil: empty content
	mixed   bool
	attrs   map[string]*attribute
}

type attribute struct {
	name     string
	typ      *simpleType
	required bool
}

type simpleType struct {
	base     string // a built-in: string, token, NMTOKEN, boolean, decimal, integer, ID, IDREF
	min, max *big.Rat
	patterns []*regexp.Regexp
}

type identity struct {
	name, refer string // refer: "" for a key, else the key a keyref refers to
	selector    []string
	field       string
}

var builtins = map[string]bool{"string": true, "token": true, "NMTOKEN": true, "boolean": true, "decimal": true,
	"integer": true, "ID": true, "IDREF": true}

// Compile reads the schema file main; include resolves an xs:include's schemaLocation to its text.
func Compile(main string, include func(string) ([]byte, error)) (*Schema, error) {
	s := &Schema{elements: map[string]*element{}, complex: map[string]*complexType{}, simple: map[string]*simpleType{}}
	if err := s.read(main, include, map[string]bool{}); err != nil {
		return nil, err
	}
	for _, f := range s.pending {
		if err := f(); err != nil {
			return nil, err
		}
	}
	return s, nil
}

func (s *Schema) read(file string, include func(string) ([]byte, error), seen map[string]bool) error {
	if seen[file] {
		return nil
	}
	seen[file] = true
	src, err := include(file)
	if err != nil {
		return err
	}
	root, err := parseNode(src)
	if err != nil || root.name != "schema" {
		return fmt.Errorf("%s: not a schema: %v", file, err)
	}
	for _, c := range root.children {
		switch c.name {
		case "annotation":
		case "include":
			if err := s.read(c.attr("schemaLocation"), include, seen); err != nil {
				return err
			}
		case "simpleType":
			st, err := s.simpleType(c)
			if err != nil {
				return err
			}
			s.simple[c.attr("name")] = st
		case "complexType":
			ct := &complexType{}
			s.complex[c.attr("name")] = ct
			if err := s.fillComplex(ct, c); err != nil {
				return err
			}
		case "element":
			e, err := s.element(c)
			if err != nil {
				return err
			}
			s.elements[e.name] = e
		default:
			return fmt.Errorf("%s: <xs:%s> is not supported", file, c.name)
		}
	}
	return nil
}

func occurs(n *node) (int, int, error) {
	lo, hi := 1, 1
	var err error
	if v := n.attr("minOccurs"); v != "" {
		if lo, err = strconv.Atoi(v); err != nil {
			return 0, 0, err
		}
	}
	switch v := n.attr("maxOccurs"); v {
	case "":
	case "unbounded":
		hi = -1
	default:
		if hi, err = strconv.Atoi(v); err != nil {
			return 0, 0, err
		}
	}
	return lo, hi, nil
}

// typeRef resolves type="..." once every file is read.
func (s *Schema) typeRef(name string, set func(*complexType)) {
	s.pending = append(s.pending, func() error {
		ct, ok := s.complex[name]
		if !ok {
			return fmt.Errorf("unknown complex type %q", name)
		}
		set(ct)
		return nil
	})
}

func (s *Schema) element(n *node) (*element, error) {
	e := &element{name: n.attr("name")}
	if t := n.attr("type"); t != "" {
		s.typeRef(t, func(ct *complexType) { e.typ = ct })
	}
	for _, c := range n.children {
		switch c.name {
		case "annotation":
		case "complexType":
			e.typ = &complexType{}
			if err := s.fillComplex(e.typ, c); err != nil {
				return nil, err
			}
		case "key", "keyref":
			id := &identity{name: c.attr("name"), refer: c.attr("refer")}
			for _, f := range c.children {
				switch f.name {
				case "selector":
					id.selector = strings.Split(f.attr("xpath"), "/")
				case "field":
					id.field = strings.TrimPrefix(f.attr("xpath"), "@")
				}
			}
			if id.field == "" || len(id.selector) == 0 || (c.name == "keyref" && id.refer == "") {
				return nil, fmt.Errorf("element %s: identity constraint %s not supported", e.name, id.name)
			}
			e.constraints = append(e.constraints, id)
		default:
			return nil, fmt.Errorf("element %s: <xs:%s> is not supported", e.name, c.name)
		}
	}
	return e, nil
}

func (s *Schema) fillComplex(ct *complexType, n *node) error {
	ct.mixed = n.attr("mixed") == "true"
	ct.attrs = map[string]*attribute{}
	for _, c := range n.children {
		switch c.name {
		case "annotation":
		case "sequence", "choice":
			p, err := s.group(c)
			if err != nil {
				return err
			}
			ct.content = p
		case "attribute":
			a := &attribute{name: c.attr("name"), required: c.attr("use") == "required"}
			if t := c.attr("type"); t != "" {
				st, err := s.simpleRef(t)
				if err != nil {
					return err
				}
				if st == nil {
					s.pending = append(s.pending, func() error {
						named, ok := s.simple[t]
						if !ok {
							return fmt.Errorf("unknown simple type %q", t)
						}
						a.typ = named
						return nil
					})
				}
				a.typ = st
			}
			for _, sc := range c.children {
				if sc.name == "simpleType" {
					st, err := s.simpleType(sc)
					if err != nil {
						return err
					}
					a.typ = st
				}
			}
			if a.typ == nil && c.attr("type") == "" {
				a.typ = &simpleType{base: "string"}
			}
			ct.attrs[a.name] = a
		default:
			return fmt.Errorf("complex type: <xs:%s> is not supported", c.name)
		}
	}
	return nil
}

// simpleRef is a built-in type now, or nil for a named type resolved later.
func (s *Schema) simpleRef(t string) (*simpleType, error) {
	if b, ok := strings.CutPrefix(t, "xs:"); ok {
		if !builtins[b] {
			return nil, fmt.Errorf("built-in type %s is not supported", t)
		}
		return &simpleType{base: b}, nil
	}
	return nil, nil
}

func (s *Schema) group(n *node) (*particle, error) {
	lo, hi, err := occurs(n)
	if err != nil {
		return nil, err
	}
	p := &particle{seq: n.name == "sequence", min: lo, max: hi}
	for _, c := range n.children {
		switch c.name {
		case "annotation":
		case "element":
			lo, hi, err := occurs(c)
			if err != nil {
				return nil, err
			}
			item := &particle{min: lo, max: hi}
			if ref := c.attr("ref"); ref != "" {
				s.pending = append(s.pending, func() error {
					e, ok := s.elements[ref]
					if !ok {
						return fmt.Errorf("unknown element %q", ref)
					}
					item.elem = e
					return nil
				})
			} else if item.elem, err = s.element(c); err != nil {
				return nil, err
			}
			p.items = append(p.items, item)
		case "sequence", "choice":
			sub, err := s.group(c)
			if err != nil {
				return nil, err
			}
			p.items = append(p.items, sub)
		default:
			return nil, fmt.Errorf("group: <xs:%s> is not supported", c.name)
		}
	}
	return p, nil
}

func (s *Schema) simpleType(n *node) (*simpleType, error) {
	for _, c := range n.children {
		if c.name != "restriction" {
			continue
		}
		base, ok := strings.CutPrefix(c.attr("base"), "xs:")
		if !ok || !builtins[base] {
			return nil, fmt.Errorf("restriction of %q is not supported", c.attr("base"))
		}
		st := &simpleType{base: base}
		for _, f := range c.children {
			v := f.attr("value")
			switch f.name {
			case "annotation":
			case "minInclusive", "maxInclusive":
				r, ok := new(big.Rat).SetString(v)
				if !ok {
					return nil, fmt.Errorf("facet %s=%q", f.name, v)
				}
				if f.name == "minInclusive" {
					st.min = r
				} else {
					st.max = r
				}
			case "pattern":
				re, err := regexp.Compile("^(?:" + v + ")$") // XSD patterns match the whole value
				if err != nil {
					return nil, err
				}
				st.patterns = append(st.patterns, re)
			default:
				return nil, fmt.Errorf("facet <xs:%s> is not supported", f.name)
			}
		}
		return st, nil
	}
	return nil, fmt.Errorf("simple type without a restriction")
}
