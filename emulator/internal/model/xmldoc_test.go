package model

import (
	"strings"
	"testing"
)

func TestCheckDocument(t *testing.T) {
	deep := strings.Repeat("<a>", 64) + strings.Repeat("</a>", 64)
	for _, c := range []struct {
		doc, root string
		ok        bool
	}{
		{`<map/>`, "map", true},
		{"\xef\xbb\xbf<?xml version=\"1.0\"?>\n<map>\n</map>\n<!-- end -->", "map", true},
		{`<?xml version="1.0" encoding="ISO-8859-1"?><map t="` + "\xfc" + `"/>`, "map", true},
		{`<?xml version="1.0" encoding="UTF-8"?><map t="` + "\xfc" + `"/>`, "map", false},
		{`<?xml version="1.0" encoding="EBCDIC"?><map/>`, "map", false},
		{`<!DOCTYPE map SYSTEM "map.dtd"><map/>`, "map", true},
		{`<!DOCTYPE map [<!ELEMENT map EMPTY>]><map/>`, "map", true},
		{`<!DOCTYPE map [<!ENTITY % p "x">]><map/>`, "map", false},
		{`<map>&undefined;</map>`, "map", false},
		{`<map>&amp;&#65;</map>`, "map", true},
		{`<roadmap/>`, "map", false},
		{`<x:map xmlns:x="urn:x"/>`, "map", false},
		{`<map/><map/>`, "map", false},
		{`<map/>trailing`, "map", false},
		{``, "map", false},
		{`<map>` + deep + `</map>`, "map", false},
		{strings.Repeat("<a>", 63) + strings.Repeat("</a>", 63), "a", true},
	} {
		err := checkDocument([]byte(c.doc), c.root)
		if (err == nil) != c.ok {
			t.Errorf("%.60q as <%s>: error %v, want ok=%v", c.doc, c.root, err, c.ok)
		}
	}
}
