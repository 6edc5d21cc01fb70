package xsd

// xs:key and xs:keyref with a child-path selector ("stations/station") and one attribute field ("@id"):
// the key's values are present and unique, every keyref value names one of them (E-XML-014).

import "fmt"

func (v *validation) identity(e *elem, id *identity, decl *element) error {
	selected := selectPath(e, id.selector)
	if id.refer == "" {
		keys := map[string]bool{}
		for _, s := range selected {
			val, ok := s.get(id.field)
			if !ok {
				return fmt.Errorf("line %d: key %s: <%s> lacks %q", s.line, id.name, s.name, id.field)
			}
			if keys[val] {
				return fmt.Errorf("line %d: key %s: %q twice", s.line, id.name, val)
			}
			keys[val] = true
		}
		return nil
	}
	var key *identity
	for _, k := range decl.constraints {
		if k.name == id.refer && k.refer == "" {
			key = k
		}
	}
	if key == nil {
		return fmt.Errorf("keyref %s: no key %s", id.name, id.refer)
	}
	values := map[string]bool{}
	for _, s := range selectPath(e, key.selector) {
		if val, ok := s.get(key.field); ok {
			values[val] = true
		}
	}
	for _, s := range selected {
		if val, ok := s.get(id.field); ok && !values[val] {
			return fmt.Errorf("line %d: %s %q names no %s", s.line, id.field, val, id.refer)
		}
	}
	return nil
}

func selectPath(e *elem, path []string) []*elem {
	selected := []*elem{e}
	for _, step := range path {
		var next []*elem
		for _, s := range selected {
			for _, c := range s.children {
				if c.name == step {
					next = append(next, c)
				}
			}
		}
		selected = next
	}
	return selected
}
