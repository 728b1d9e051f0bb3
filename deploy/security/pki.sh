#!/usr/bin/env bash
# The cell's DDS Security material (OMG DDS-Security 1.1, Cyclone DDS's
# builtin plugins), made with OpenSSL:
#
#   deploy/security/pki.sh init DIR [--machines mill-1,mill-2]
#       an identity CA and a permissions CA (EC P-256), the governance
#       document, and for the cell, each edge and the dashboard an identity
#       certificate and key, a permissions document (signed) and a Cyclone
#       DDS profile (loopback, with its Security section)
#   deploy/security/pki.sh issue DIR NAME ROLE [MACHINE]
#       one more participant (ROLE: cell, edge, dashboard, observer; an edge
#       names its MACHINE, the only one whose partition it may use), or a
#       new certificate for an existing one (rotation: the old one stays
#       valid until it expires or is revoked)
#   deploy/security/pki.sh https DIR NAME [HOST...]
#       an HTTPS server certificate for NAME (the dashboard) naming HOSTs
#       (host names or IP addresses; default localhost and 127.0.0.1),
#       signed by the web CA (ca/web_ca.pem, made on first use): the one
#       certificate a browser or curl is told to trust. Writes
#       NAME/https.pem and NAME/https.key (smc-dashboard --tls-cert/--tls-key)
#   deploy/security/pki.sh revoke DIR NAME
#       re-signs NAME's permissions with a validity that ended (it is refused
#       from its next handshake on) and moves its identity aside
#
# Layout of DIR: ca/ (identity_ca.pem, permissions_ca.pem and their keys),
# governance.p7s, NAME/{identity.pem,identity.key,permissions.p7s,
# cyclonedds.xml,security.xml}. Point a process at NAME/cyclonedds.xml with
# CYCLONEDDS_URI=file://DIR/NAME/cyclonedds.xml (the loopback profile), or
# add NAME/security.xml to another profile (the smc image's entry point does,
# with SMC_DDS_SECURITY=DIR/NAME/security.xml).
set -euo pipefail

usage() { sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit "${1:-2}"; }
case "${1:-}" in -h | --help) usage 0 ;; esac
[[ $# -ge 2 ]] || usage 2
cmd=$1
dir=$(realpath -m "$2")
shift 2
days=365

subject() { echo "/C=XX/O=SMC cell/CN=$1"; }

ca() {  # ca NAME
  local n=$1
  openssl ecparam -name prime256v1 -genkey -noout -out "$dir/ca/$n.key" 2>/dev/null
  openssl req -x509 -new -key "$dir/ca/$n.key" -sha256 -days $((days * 5)) \
    -subj "$(subject "SMC $n")" -out "$dir/ca/$n.pem" 2>/dev/null
  chmod 600 "$dir/ca/$n.key"
}

sign() {  # sign IN.xml OUT.p7s: S/MIME signed by the permissions CA
  openssl smime -sign -in "$1" -text -out "$2" -signer "$dir/ca/permissions_ca.pem" \
    -inkey "$dir/ca/permissions_ca.key" 2>/dev/null
}

rule() {  # rule TOPIC_EXPRESSION DISCOVERY_PROTECTED METADATA_PROTECTION
  cat <<XML
        <topic_rule>
          <topic_expression>$1</topic_expression>
          <enable_discovery_protection>$2</enable_discovery_protection>
          <enable_liveliness_protection>false</enable_liveliness_protection>
          <enable_read_access_control>true</enable_read_access_control>
          <enable_write_access_control>true</enable_write_access_control>
          <metadata_protection_kind>$3</metadata_protection_kind>
          <data_protection_kind>NONE</data_protection_kind>
        </topic_rule>
XML
}

governance() {
  cat >"$dir/governance.xml" <<XML
<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-Security/20170801/omg_shared_ca_governance.xsd">
  <domain_access_rules>
    <domain_rule>
      <domains><id_range><min>0</min><max>230</max></id_range></domains>
      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>
      <enable_join_access_control>true</enable_join_access_control>
      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>
      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>
      <rtps_protection_kind>NONE</rtps_protection_kind>
      <topic_access_rules>
        <!-- Configuration, assignments, operator commands: access-controlled and signed. -->
$(for t in smc_config smc_job smc_operator_command; do rule "$t" true SIGN; done)
        <!-- Telemetry, status, events: access-controlled, not signed (cost). -->
$(rule '*' false NONE)
      </topic_access_rules>
    </domain_rule>
  </domain_access_rules>
</dds>
XML
  sign "$dir/governance.xml" "$dir/governance.p7s"
}

# What each role may publish and subscribe (topic names in idl/README.md).
grants() {  # grants ROLE
  case "$1" in
    cell) echo "pub:* sub:*" ;;
    edge) echo "pub:smc_force_summary,smc_force_batch,smc_chatter_event,smc_supervisor_situation,smc_edge_status,smc_job_progress,smc_program sub:smc_config,smc_job,smc_operator_command" ;;
    dashboard) echo "pub:smc_operator_command sub:*" ;;
    observer) echo "pub: sub:*" ;;
    *) echo "pki.sh: unknown role '$1' (cell, edge, dashboard, observer)" >&2; exit 2 ;;
  esac
}

topics_xml() {  # topics_xml LIST
  local t
  IFS=, read -ra list <<<"$1"
  for t in "${list[@]}"; do [[ -n "$t" ]] && echo "            <topic>$t</topic>"; done
}

permissions() {  # permissions NAME ROLE MACHINE [NOT_AFTER]
  local name=$1 role=$2 machine=$3 not_after=${4:-2036-01-01T00:00:00}
  local g pub sub part='*'
  # An edge publishes and reads only in its machine's partition,
  # "<cell partition>/machine/<machine>" (idl/README.md): it cannot act as
  # another machine. The others: every partition of every cell.
  [[ "$role" == edge ]] && part="*/machine/$machine"
  g=$(grants "$role")
  pub=${g%% sub:*}; pub=${pub#pub:}
  sub=${g##* sub:}
  {
    cat <<XML
<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-Security/20170801/omg_shared_ca_permissions.xsd">
  <permissions>
    <grant name="$name">
      <subject_name>$(openssl x509 -in "$dir/$name/identity.pem" -noout -subject -nameopt RFC2253 | sed 's/^subject=//')</subject_name>
      <validity><not_before>2020-01-01T00:00:00</not_before><not_after>$not_after</not_after></validity>
      <allow_rule>
        <domains><id_range><min>0</min><max>230</max></id_range></domains>
XML
    # Topics as the role allows, in the partitions it may use.
    if [[ -n "$pub" ]]; then
      echo "        <publish><topics>"; topics_xml "$pub"
      echo "        </topics><partitions><partition>$part</partition></partitions></publish>"
    fi
    if [[ -n "$sub" ]]; then
      echo "        <subscribe><topics>"; topics_xml "$sub"
      echo "        </topics><partitions><partition>$part</partition></partitions></subscribe>"
    fi
    cat <<XML
      </allow_rule>
      <default>DENY</default>
    </grant>
  </permissions>
</dds>
XML
  } >"$dir/$name/permissions.xml"
  sign "$dir/$name/permissions.xml" "$dir/$name/permissions.p7s"
}

security_xml() {  # security_xml NAME: its Security section, alone (a Cyclone DDS fragment)
  local d="$dir/$1"
  cat >"$d/security.xml" <<XML
<Security>
  <Authentication>
    <Library path="dds_security_auth" initFunction="init_authentication" finalizeFunction="finalize_authentication"/>
    <IdentityCA>file:$dir/ca/identity_ca.pem</IdentityCA>
    <IdentityCertificate>file:$d/identity.pem</IdentityCertificate>
    <PrivateKey>file:$d/identity.key</PrivateKey>
  </Authentication>
  <AccessControl>
    <Library path="dds_security_ac" initFunction="init_access_control" finalizeFunction="finalize_access_control"/>
    <PermissionsCA>file:$dir/ca/permissions_ca.pem</PermissionsCA>
    <Governance>file:$dir/governance.p7s</Governance>
    <Permissions>file:$d/permissions.p7s</Permissions>
  </AccessControl>
  <Cryptographic>
    <Library path="dds_security_crypto" initFunction="init_crypto" finalizeFunction="finalize_crypto"/>
  </Cryptographic>
</Security>
XML
}

profile() {  # profile NAME: the loopback profile with NAME's Security section
  local d="$dir/$1"
  security_xml "$1"
  cat >"$d/cyclonedds.xml" <<XML
<?xml version="1.0" encoding="UTF-8"?>
<!-- $1: the loopback profile (deploy/cyclonedds/loopback.xml) with DDS Security. -->
<CycloneDDS xmlns="https://cdds.io/config">
  <Domain id="any">
    <General>
      <Interfaces><NetworkInterface name="lo"/></Interfaces>
      <AllowMulticast>false</AllowMulticast>
    </General>
    <Discovery>
      <ParticipantIndex>auto</ParticipantIndex>
      <MaxAutoParticipantIndex>119</MaxAutoParticipantIndex>
      <Peers><Peer address="127.0.0.1"/></Peers>
    </Discovery>
$(sed 's/^/    /' "$d/security.xml")
  </Domain>
</CycloneDDS>
XML
}

issue() {  # issue NAME ROLE [MACHINE]
  local name=$1 role=$2 machine=${3:-} d="$dir/$1"
  grants "$role" >/dev/null
  if [[ "$role" == edge ]]; then
    # The machine id names a DDS partition (smc::transport::machine_partition).
    if [[ ! "$machine" =~ ^[A-Za-z0-9][A-Za-z0-9._-]{0,30}$ ]]; then
      echo "pki.sh: issue $name edge: give the edge's MACHINE id (a letter or digit, then" \
        "up to 30 letters, digits, '-', '_' or '.'), e.g. pki.sh issue DIR edge-mill-3 edge mill-3" >&2
      exit 2
    fi
  elif [[ -n "$machine" ]]; then
    echo "pki.sh: issue $name $role: only an edge takes a MACHINE" >&2
    exit 2
  fi
  mkdir -p "$d"
  openssl ecparam -name prime256v1 -genkey -noout -out "$d/identity.key" 2>/dev/null
  chmod 600 "$d/identity.key"
  openssl req -new -key "$d/identity.key" -subj "$(subject "$name")" -out "$d/identity.csr" 2>/dev/null
  openssl x509 -req -in "$d/identity.csr" -CA "$dir/ca/identity_ca.pem" -CAkey "$dir/ca/identity_ca.key" \
    -CAcreateserial -days "$days" -sha256 -out "$d/identity.pem" 2>/dev/null
  rm -f "$d/identity.csr"
  echo "$role" >"$d/role"
  echo "$machine" >"$d/machine"
  permissions "$name" "$role" "$machine"
  profile "$name"
  echo "$name ($role${machine:+ of $machine}): $d/cyclonedds.xml"
}

https_cert() {  # https_cert NAME [HOST...]
  local name=$1 d="$dir/$1" h san=()
  shift
  local hosts=("$@")
  [[ ${#hosts[@]} -gt 0 ]] || hosts=(localhost 127.0.0.1)
  for h in "${hosts[@]}"; do
    if [[ $h =~ ^[0-9.]+$ || $h == *:* ]]; then san+=("IP:$h"); else san+=("DNS:$h"); fi
  done
  mkdir -p "$dir/ca" "$d"
  [[ -f "$dir/ca/web_ca.pem" ]] || ca web_ca
  openssl ecparam -name prime256v1 -genkey -noout -out "$d/https.key" 2>/dev/null
  chmod 600 "$d/https.key"
  openssl req -new -key "$d/https.key" -subj "$(subject "$name")" -out "$d/https.csr" 2>/dev/null
  printf 'subjectAltName=%s\nbasicConstraints=critical,CA:FALSE\nkeyUsage=critical,digitalSignature\nextendedKeyUsage=serverAuth\n' \
    "$(IFS=,; echo "${san[*]}")" >"$d/https.ext"
  openssl x509 -req -in "$d/https.csr" -CA "$dir/ca/web_ca.pem" -CAkey "$dir/ca/web_ca.key" \
    -CAcreateserial -days "$days" -sha256 -extfile "$d/https.ext" -out "$d/https.pem" 2>/dev/null
  rm -f "$d/https.csr" "$d/https.ext"
  echo "$name (HTTPS for ${hosts[*]}): $d/https.pem, $d/https.key; trust $dir/ca/web_ca.pem"
}

case "$cmd" in
  init)
    machines=mill-1,mill-2
    while [[ $# -gt 0 ]]; do
      case "$1" in
        --machines) machines=$2; shift 2 ;;
        *) usage ;;
      esac
    done
    mkdir -p "$dir/ca"
    ca identity_ca
    ca permissions_ca
    governance
    issue cell cell
    IFS=, read -ra ms <<<"$machines"
    for m in "${ms[@]}"; do issue "edge-$m" edge "$m"; done
    issue dashboard dashboard
    ;;
  issue)
    [[ $# -ge 2 ]] || usage
    issue "$1" "$2" "${3:-}"
    ;;
  https)
    [[ $# -ge 1 ]] || usage
    https_cert "$@"
    ;;
  revoke)
    [[ $# -ge 1 ]] || usage
    [[ -d "$dir/$1" ]] || { echo "pki.sh: no participant '$1' in $dir" >&2; exit 2; }
    permissions "$1" "$(cat "$dir/$1/role")" "$(cat "$dir/$1/machine" 2>/dev/null || true)" \
      2020-01-02T00:00:00
    mv "$dir/$1/identity.key" "$dir/$1/identity.key.revoked"
    echo "$1: permissions expired (2020-01-02), key moved aside"
    ;;
  *) usage ;;
esac
