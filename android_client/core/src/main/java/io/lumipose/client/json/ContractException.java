package io.lumipose.client.json;

/** JSON that breaks the contract; {@link #field} names the offending field (dotted path). */
public final class ContractException extends IllegalArgumentException {
    private static final long serialVersionUID = 1L;
    public final String field;

    /** What is wrong, without the field's name. */
    public final String reason;

    public ContractException(String field, String message) {
        super(field + ": " + message);
        this.field = field;
        this.reason = message;
    }

    /** The same problem named from an enclosing document: {@code prefix} + field ("map." + "beacons[0].id"). */
    public ContractException within(String prefix) {
        return new ContractException(prefix + field, reason);
    }
}
