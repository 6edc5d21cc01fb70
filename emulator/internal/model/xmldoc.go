package model

// What the emulator checks of a document (guide 6.5; E-XML-011, E-XML-012, E-XML-021, E-XML-001 ff.): that it
// is one well-formed XML document in its declared encoding, with the right root element, no entity
// declarations and at most 64 levels of nesting, valid against its schema of spec/schemas (internal/xsd).
// A document that passes is kept as sent.

import (
	"bytes"
	"encoding/xml"
	"errors"
	"fmt"
	"io"
	"os"
	"strings"

	"pltf/emulator/internal/xsd"
)

// schemas: the compiled XSD of each kind (the text generated from spec/schemas into internal/xsd).
var schemas = func() [3]*xsd.Schema {
	var out [3]*xsd.Schema
	for k, file := range [...]string{"map.xsd", "roadmap.xsd", "program.xsd"} {
		s, err := xsd.Compile(file, func(name string) ([]byte, error) {
			if src, ok := xsd.Files[name]; ok {
				return []byte(src), nil
			}
			return nil, os.ErrNotExist
		})
		if err != nil {
			panic("the schemas of spec/schemas do not compile: " + err.Error()) // our own data: a test catches it
		}
		out[k] = s
	}
	return out
}()

var docRoots = [...]string{"map", "roadmap", "program"}

// maxDepth: element nesting allowed (E-XML-021).
const maxDepth = 64

// charsetReader decodes the single-byte encodings a 2006 Windows program may have declared (E-XML-011);
// UTF-8 is encoding/xml's own. windows-1252 is read as ISO-8859-1: both are one byte per character, which is
// all a well-formedness check needs.
func charsetReader(label string, in io.Reader) (io.Reader, error) {
	switch strings.ToLower(label) {
	case "iso-8859-1", "iso8859-1", "latin1", "latin-1", "l1", "us-ascii", "ascii", "windows-1252", "cp1252":
		b, err := io.ReadAll(in)
		if err != nil {
			return nil, err
		}
		return strings.NewReader(latin1(b)), nil
	}
	return nil, fmt.Errorf("unsupported encoding %q", label)
}

func newDecoder(doc []byte) *xml.Decoder { return readerDecoder(bytes.NewReader(doc)) }

func readerDecoder(r io.Reader) *xml.Decoder {
	b, _ := io.ReadAll(r)
	d := xml.NewDecoder(bytes.NewReader(bytes.TrimPrefix(b, []byte("\xef\xbb\xbf"))))
	d.Strict = true
	d.CharsetReader = charsetReader
	return d
}

// checkKind is checkDocument with the root element of kind k, then its schema.
func checkKind(doc []byte, k DocKind) error {
	if err := checkDocument(doc, docRoots[k]); err != nil {
		return err
	}
	if err := schemas[k].Validate(doc, readerDecoder); err != nil {
		return fmt.Errorf("invalid %s: %v", k, err)
	}
	return nil
}

// checkDocument refuses a document that is not one well-formed XML document with root element root.
func checkDocument(doc []byte, root string) error {
	d := newDecoder(doc)
	depth, roots := 0, 0
	for {
		tok, err := d.Token()
		if err == io.EOF {
			break
		}
		if err != nil {
			return fmt.Errorf("not well-formed: %v", err)
		}
		switch t := tok.(type) {
		case xml.StartElement:
			if depth == 0 {
				roots++
				if roots > 1 {
					return errors.New("not well-formed: more than one root element")
				}
				if t.Name.Local != root || t.Name.Space != "" {
					return fmt.Errorf("the root element is <%s>, not <%s>", t.Name.Local, root)
				}
			}
			if depth++; depth > maxDepth {
				return fmt.Errorf("nested deeper than %d elements (E-XML-021)", maxDepth)
			}
		case xml.EndElement:
			depth--
		case xml.Directive:
			if bytes.Contains(t, []byte("<!ENTITY")) {
				return errors.New("entity declarations are not allowed (E-XML-012)")
			}
		case xml.CharData:
			if depth == 0 && len(bytes.TrimSpace(t)) > 0 {
				return errors.New("not well-formed: text outside the root element")
			}
		}
	}
	if roots == 0 {
		return errors.New("not well-formed: no root element")
	}
	return nil
}
